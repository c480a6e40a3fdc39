#include "support/test_meshes.h"

#include "voxd/voxelize/voxelize.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <stdexcept>

#include <glm/geometric.hpp>

namespace voxd::test {
namespace {

std::uint32_t add_vertex(Mesh& m, glm::dvec3 p) {
  m.vertices.emplace_back(p);
  return static_cast<std::uint32_t>(m.vertices.size() - 1);
}

}  // namespace

BitVolume random_volume(const glm::i64vec3& dims, double density, std::mt19937& rng) {
  BitVolume v(unit_grid(dims));
  std::bernoulli_distribution fill(density);
  for (std::int64_t k = 0; k < dims.z; ++k)
    for (std::int64_t j = 0; j < dims.y; ++j)
      for (std::int64_t i = 0; i < dims.x; ++i) v.set(i, j, k, fill(rng));
  return v;
}

BitVolume solid_of(const Mesh& mesh, double voxel) {
  GridRequest r;
  r.kind = GridRequest::Kind::voxel_size;
  r.voxel_size = voxel;
  r.padding = 2;
  return voxelize_parity(mesh, resolve_grid(r, bounds(mesh)), 0, 0, nullptr);
}

Mesh make_box(glm::dvec3 lo, glm::dvec3 hi) {
  Mesh m;
  for (int c = 0; c < 8; ++c)
    add_vertex(m, {(c & 1) ? hi.x : lo.x, (c & 2) ? hi.y : lo.y, (c & 4) ? hi.z : lo.z});
  // Outward CCW faces.
  const std::uint32_t f[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : f) {
    m.triangles.push_back({q[0], q[1], q[2]});
    m.triangles.push_back({q[0], q[2], q[3]});
  }
  return m;
}

Mesh make_icosphere(glm::dvec3 center, double radius, int level) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<glm::dvec3> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                               {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (auto& p : v) p = glm::normalize(p);
  std::vector<std::array<std::uint32_t, 3>> f = {
      {0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
      {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
      {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
    auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back(glm::normalize(v[a] + v[b]));
      const auto idx = static_cast<std::uint32_t>(v.size() - 1);
      mid.emplace(key, idx);
      return idx;
    };
    std::vector<std::array<std::uint32_t, 3>> nf;
    nf.reserve(f.size() * 4);
    for (const auto& tri : f) {
      const std::uint32_t a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), c = midpoint(tri[2], tri[0]);
      nf.push_back({tri[0], a, c});
      nf.push_back({tri[1], b, a});
      nf.push_back({tri[2], c, b});
      nf.push_back({a, b, c});
    }
    f.swap(nf);
  }
  Mesh m;
  for (const auto& p : v) add_vertex(m, center + radius * p);
  m.triangles.assign(f.begin(), f.end());
  return m;
}

Mesh make_torus(glm::dvec3 center, double R, double r, int nu, int nv) {
  Mesh m;
  const double two_pi = 2.0 * M_PI;
  for (int i = 0; i < nu; ++i) {
    const double u = two_pi * i / nu;
    for (int j = 0; j < nv; ++j) {
      const double w = two_pi * j / nv;
      add_vertex(m, center + glm::dvec3((R + r * std::cos(w)) * std::cos(u), (R + r * std::cos(w)) * std::sin(u),
                                        r * std::sin(w)));
    }
  }
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>((i % nu) * nv + (j % nv)); };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const std::uint32_t a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
      m.triangles.push_back({a, b, c});
      m.triangles.push_back({a, c, d});
    }
  return m;
}

Mesh make_extrusion(const std::vector<glm::dvec2>& outline, double y0, double y1) {
  Mesh m;
  const auto n = static_cast<std::uint32_t>(outline.size());
  for (const glm::dvec2& p : outline) add_vertex(m, {p.x, y0, p.y});
  for (const glm::dvec2& p : outline) add_vertex(m, {p.x, y1, p.y});
  for (std::uint32_t i = 0; i < n; ++i) {
    const std::uint32_t j = (i + 1) % n;
    m.triangles.push_back({i, j, j + n});
    m.triangles.push_back({i, j + n, i + n});
  }
  // Ear clipping of the outline, oriented counter-clockwise first.
  double area = 0.0;
  for (std::uint32_t i = 0; i < n; ++i) {
    const glm::dvec2 a = outline[i], b = outline[(i + 1) % n];
    area += a.x * b.y - b.x * a.y;
  }
  std::vector<std::uint32_t> left(n);
  for (std::uint32_t i = 0; i < n; ++i) left[i] = area > 0 ? i : n - 1 - i;
  auto cross = [](glm::dvec2 o, glm::dvec2 a, glm::dvec2 b) { return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x); };
  while (left.size() > 3) {
    bool clipped = false;
    for (std::size_t k = 0; k < left.size() && !clipped; ++k) {
      const std::uint32_t ia = left[(k + left.size() - 1) % left.size()], ib = left[k], ic = left[(k + 1) % left.size()];
      const glm::dvec2 a = outline[ia], b = outline[ib], c = outline[ic];
      if (cross(a, b, c) <= 0) continue;  // reflex
      bool empty = true;
      for (std::uint32_t other : left) {
        if (other == ia || other == ib || other == ic) continue;
        const glm::dvec2 p = outline[other];
        if (cross(a, b, p) >= 0 && cross(b, c, p) >= 0 && cross(c, a, p) >= 0) empty = false;
      }
      if (!empty) continue;
      m.triangles.push_back({ia, ic, ib});
      m.triangles.push_back({ia + n, ib + n, ic + n});
      left.erase(left.begin() + static_cast<std::ptrdiff_t>(k));
      clipped = true;
    }
    if (!clipped) throw std::invalid_argument("make_extrusion: outline is not a simple polygon");
  }
  m.triangles.push_back({left[0], left[2], left[1]});
  m.triangles.push_back({left[0] + n, left[1] + n, left[2] + n});
  return m;
}

Mesh make_tube(double R, double r, double z0, double z1, int segments) {
  Mesh m;
  const double pi = 3.14159265358979323846;
  for (int i = 0; i < segments; ++i) {
    const double a = 2.0 * pi * i / segments;
    const double c = std::cos(a), s = std::sin(a);
    add_vertex(m, {R * c, R * s, z0});
    add_vertex(m, {R * c, R * s, z1});
    add_vertex(m, {r * c, r * s, z0});
    add_vertex(m, {r * c, r * s, z1});
  }
  for (int i = 0; i < segments; ++i) {
    const auto b = static_cast<std::uint32_t>(4 * i), e = static_cast<std::uint32_t>(4 * ((i + 1) % segments));
    auto quad = [&](std::uint32_t p, std::uint32_t q, std::uint32_t r2, std::uint32_t s2) {
      m.triangles.push_back({p, q, r2});
      m.triangles.push_back({p, r2, s2});
    };
    quad(b, e, e + 1, b + 1);          // outer wall
    quad(b + 2, b + 3, e + 3, e + 2);  // inner wall
    quad(b + 1, e + 1, e + 3, b + 3);  // top
    quad(b, b + 2, e + 2, e);          // bottom
  }
  return m;
}

Mesh rotated(Mesh mesh, double degrees_x, double degrees_y) {
  const double ax = degrees_x * 3.14159265358979323846 / 180.0, ay = degrees_y * 3.14159265358979323846 / 180.0;
  for (auto& v : mesh.vertices) {
    const glm::dvec3 p(v);
    const glm::dvec3 q{p.x, p.y * std::cos(ax) - p.z * std::sin(ax), p.y * std::sin(ax) + p.z * std::cos(ax)};
    v = glm::vec3(glm::dvec3{q.x * std::cos(ay) + q.z * std::sin(ay), q.y, -q.x * std::sin(ay) + q.z * std::cos(ay)});
  }
  return mesh;
}

Mesh concat(const std::vector<Mesh>& parts) {
  Mesh out;
  for (const auto& p : parts) {
    const auto base = static_cast<std::uint32_t>(out.vertices.size());
    out.vertices.insert(out.vertices.end(), p.vertices.begin(), p.vertices.end());
    for (auto t : p.triangles) out.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  }
  return out;
}

Mesh flipped(Mesh mesh) {
  for (auto& t : mesh.triangles) std::swap(t[1], t[2]);
  return mesh;
}

Mesh remove_face(Mesh mesh, int axis, double value) {
  std::erase_if(mesh.triangles, [&](const auto& t) {
    for (auto v : t)
      if (mesh.vertices[v][axis] != static_cast<float>(value)) return false;
    return true;
  });
  return mesh;
}

Mesh punched(const Mesh& mesh, std::size_t stride) {
  Mesh out = mesh;
  out.triangles.clear();
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    if (t % stride != stride / 2) out.triangles.push_back(mesh.triangles[t]);
  return out;
}

Mesh soup_of(const Mesh& mesh) {
  Mesh soup;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto first = static_cast<std::uint32_t>(soup.vertices.size());
    for (int c = 0; c < 3; ++c) soup.vertices.push_back(mesh.corner(t, c));
    soup.triangles.push_back({first, first + 1, first + 2});
  }
  return soup;
}

double mesh_volume(const Mesh& mesh) {
  double vol = 0.0;
  for (const auto& t : mesh.triangles) {
    const glm::dvec3 a(mesh.vertices[t[0]]), b(mesh.vertices[t[1]]), c(mesh.vertices[t[2]]);
    vol += glm::dot(a, glm::cross(b, c));
  }
  return vol / 6.0;
}

std::vector<std::uint8_t> to_binary_stl(const Mesh& mesh, const std::string& header) {
  std::vector<std::uint8_t> out(84 + 50 * mesh.triangles.size(), 0);
  std::memcpy(out.data(), header.data(), std::min<std::size_t>(header.size(), 80));
  const auto n = static_cast<std::uint32_t>(mesh.triangles.size());
  std::memcpy(out.data() + 80, &n, 4);
  std::uint8_t* p = out.data() + 84;
  for (const auto& t : mesh.triangles) {
    const glm::vec3 a = mesh.vertices[t[0]], b = mesh.vertices[t[1]], c = mesh.vertices[t[2]];
    glm::vec3 nrm = glm::cross(b - a, c - a);
    const float len = glm::length(nrm);
    if (len > 0) nrm /= len;
    const float rec[12] = {nrm.x, nrm.y, nrm.z, a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z};
    std::memcpy(p, rec, 48);
    p += 50;
  }
  return out;
}

std::string to_ascii_stl(const Mesh& mesh) {
  std::ostringstream s;
  s.precision(9);
  s << "solid test\n";
  for (const auto& t : mesh.triangles) {
    s << "  facet normal 0 0 0\n    outer loop\n";
    for (auto v : t) s << "      vertex " << mesh.vertices[v].x << ' ' << mesh.vertices[v].y << ' ' << mesh.vertices[v].z << '\n';
    s << "    endloop\n  endfacet\n";
  }
  s << "endsolid test\n";
  return s.str();
}

std::string to_obj(const Mesh& mesh) {
  std::ostringstream s;
  s.precision(9);
  s << "# voxd test\n";
  for (const auto& v : mesh.vertices) s << "v " << v.x << ' ' << v.y << ' ' << v.z << '\n';
  for (const auto& t : mesh.triangles) s << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
  return s.str();
}

std::string to_ascii_ply(const Mesh& mesh) {
  std::ostringstream s;
  s.precision(9);
  s << "ply\nformat ascii 1.0\nelement vertex " << mesh.vertices.size()
    << "\nproperty float x\nproperty float y\nproperty float z\nelement face " << mesh.triangles.size()
    << "\nproperty list uchar int vertex_indices\nend_header\n";
  for (const auto& v : mesh.vertices) s << v.x << ' ' << v.y << ' ' << v.z << '\n';
  for (const auto& t : mesh.triangles) s << "3 " << t[0] << ' ' << t[1] << ' ' << t[2] << '\n';
  return s.str();
}

std::vector<std::uint8_t> to_binary_ply(const Mesh& mesh) {
  std::ostringstream s;
  s << "ply\nformat binary_little_endian 1.0\nelement vertex " << mesh.vertices.size()
    << "\nproperty float x\nproperty float y\nproperty float z\nelement face " << mesh.triangles.size()
    << "\nproperty list uchar uint vertex_indices\nend_header\n";
  std::string head = s.str();
  std::vector<std::uint8_t> out(head.begin(), head.end());
  auto put = [&](const void* p, std::size_t n) {
    const auto* b = static_cast<const std::uint8_t*>(p);
    out.insert(out.end(), b, b + n);
  };
  for (const auto& v : mesh.vertices) put(&v, 12);
  for (const auto& t : mesh.triangles) {
    const std::uint8_t three = 3;
    put(&three, 1);
    put(t.data(), 12);
  }
  return out;
}

std::vector<std::uint8_t> read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("test data missing: " + path);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_file(const std::string& path, const std::vector<std::uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (!out) throw std::runtime_error("cannot write " + path);
}

}  // namespace voxd::test
