#include "support/test_meshes.h"

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
  m.triangles = std::move(f);
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
