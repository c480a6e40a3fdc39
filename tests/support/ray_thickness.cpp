#include "support/ray_thickness.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <tuple>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

namespace voxd::test {
namespace {

struct Triangle {
  glm::dvec3 a, b, c;
};

Triangle triangle(const Mesh& mesh, std::size_t t) {
  return {glm::dvec3(mesh.corner(t, 0)), glm::dvec3(mesh.corner(t, 1)), glm::dvec3(mesh.corner(t, 2))};
}

// Möller–Trumbore: the ray's parameter at its crossing of the triangle, or
// nullopt; edges and corners count as crossed.
std::optional<double> hit(const Triangle& tri, glm::dvec3 origin, glm::dvec3 dir) {
  const glm::dvec3 e1 = tri.b - tri.a, e2 = tri.c - tri.a;
  const glm::dvec3 p = glm::cross(dir, e2);
  const double det = glm::dot(e1, p);
  if (std::abs(det) < 1e-300) return std::nullopt;
  const double inv = 1.0 / det;
  const glm::dvec3 s = origin - tri.a;
  const double u = glm::dot(s, p) * inv;
  if (u < -1e-12 || u > 1 + 1e-12) return std::nullopt;
  const glm::dvec3 q = glm::cross(s, e1);
  const double v = glm::dot(dir, q) * inv;
  if (v < -1e-12 || u + v > 1 + 1e-12) return std::nullopt;
  return glm::dot(e2, q) * inv;
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  const auto at = static_cast<std::size_t>(std::clamp(q, 0.0, 1.0) * static_cast<double>(v.size() - 1));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(at), v.end());
  return v[at];
}

}  // namespace

std::vector<SurfacePoint> sample_surface(const Mesh& mesh, std::size_t count, std::uint64_t seed) {
  std::vector<double> area(mesh.triangle_count());
  for (std::size_t t = 0; t < area.size(); ++t) {
    const Triangle tri = triangle(mesh, t);
    area[t] = 0.5 * glm::length(glm::cross(tri.b - tri.a, tri.c - tri.a));
  }
  std::mt19937_64 rng(seed);
  std::discrete_distribution<std::size_t> pick(area.begin(), area.end());
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<SurfacePoint> out;
  out.reserve(count);
  while (out.size() < count) {
    const std::size_t t = pick(rng);
    const Triangle tri = triangle(mesh, t);
    const glm::dvec3 n = glm::cross(tri.b - tri.a, tri.c - tri.a);
    if (glm::length(n) == 0) continue;
    double u = unit(rng), v = unit(rng);
    if (u + v > 1) u = 1 - u, v = 1 - v;
    out.push_back({tri.a + u * (tri.b - tri.a) + v * (tri.c - tri.a), glm::normalize(n), static_cast<std::uint32_t>(t)});
  }
  return out;
}

std::optional<RayHit> ray_hit(const Mesh& mesh, const SurfacePoint& p) {
  const glm::dvec3 dir = -p.normal;
  // Past the point's own plane by a hair: not its own face nor a neighbour
  // through the shared edge.
  constexpr double kSelf = 1e-7;
  std::optional<RayHit> nearest;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    if (t == p.triangle) continue;
    const Triangle tri = triangle(mesh, t);
    const auto s = hit(tri, p.point, dir);
    if (s && *s > kSelf && (!nearest || *s < nearest->distance)) {
      const glm::dvec3 n = glm::cross(tri.b - tri.a, tri.c - tri.a);
      nearest = RayHit{*s, glm::length(n) > 0 ? glm::normalize(n) : glm::dvec3(0.0)};
    }
  }
  return nearest;
}

std::optional<double> ray_thickness(const Mesh& mesh, const SurfacePoint& p) {
  const std::optional<RayHit> h = ray_hit(mesh, p);
  return h ? std::optional(h->distance) : std::nullopt;
}

std::vector<Segment> sharp_edges(const Mesh& mesh, double degrees) {
  // Vertices welded by position, then each edge's triangles.
  std::map<std::tuple<float, float, float>, std::uint32_t> welded;
  std::vector<std::uint32_t> id(mesh.vertices.size());
  std::vector<glm::dvec3> position;
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    const glm::vec3 v = mesh.vertices[i];
    const auto [it, added] = welded.emplace(std::make_tuple(v.x, v.y, v.z), static_cast<std::uint32_t>(position.size()));
    if (added) position.emplace_back(v);
    id[i] = it->second;
  }
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<glm::dvec3>> normals;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const Triangle tri = triangle(mesh, t);
    const glm::dvec3 n = glm::cross(tri.b - tri.a, tri.c - tri.a);
    if (glm::length(n) == 0) continue;
    for (int e = 0; e < 3; ++e) {
      std::uint32_t a = id[mesh.triangles[t][e]], b = id[mesh.triangles[t][(e + 1) % 3]];
      if (a > b) std::swap(a, b);
      normals[{a, b}].push_back(glm::normalize(n));
    }
  }
  const double cos_limit = std::cos(degrees * M_PI / 180.0);
  std::vector<Segment> out;
  for (const auto& [edge, n] : normals) {
    // An edge of one triangle (open) or of more than two is an edge too.
    const bool sharp = n.size() != 2 || glm::dot(n[0], n[1]) < cos_limit;
    if (sharp) out.emplace_back(position[edge.first], position[edge.second]);
  }
  return out;
}

double distance_to_edges(glm::dvec3 p, const std::vector<Segment>& edges) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& [a, b] : edges) {
    const glm::dvec3 ab = b - a;
    const double len2 = glm::dot(ab, ab);
    const double s = len2 > 0 ? std::clamp(glm::dot(p - a, ab) / len2, 0.0, 1.0) : 0.0;
    best = std::min(best, glm::length(p - (a + s * ab)));
  }
  return best;
}

namespace {
const double kFacingCos = std::cos(170.0 * 3.14159265358979323846 / 180.0);
}  // namespace

WallAgreement compare_with_rays(const Mesh& mesh, const BitVolume& solid, const DenseVolume<float>& map,
                                std::size_t count, double edge_margin, std::uint64_t seed) {
  const Grid& g = solid.grid();
  const double h = g.voxel_size;
  const std::vector<Segment> edges = sharp_edges(mesh, 30.0);
  auto voxel_of = [&](glm::dvec3 p) { return glm::i64vec3(glm::floor((p - g.origin) / h)); };
  auto inside = [&](glm::i64vec3 v) {
    return v.x >= 0 && v.y >= 0 && v.z >= 0 && v.x < g.dims.x && v.y < g.dims.y && v.z < g.dims.z &&
           solid.get(v.x, v.y, v.z);
  };
  std::vector<double> errors, read, rays;
  for (const SurfacePoint& p : sample_surface(mesh, count * 4, seed)) {
    if (errors.size() == count) break;
    const double to_edge = distance_to_edges(p.point, edges);
    if (to_edge < edge_margin * h) continue;
    const std::optional<RayHit> exit = ray_hit(mesh, p);
    if (!exit) continue;
    const std::optional<double> ray = exit->distance;
    // A face whose ray runs on for more than twice its distance to an edge
    // ends a wall (a tube's annular cap reads the tube's length): the wall
    // it ends is measured on the wall's own faces.
    if (*ray > 2 * to_edge) continue;
    // The same at the far end: a ray that leaves within half its length of
    // an edge leaves by the end of a wall (behind a rib, a bore's ray runs
    // out along the rib to its rim), measuring the wall's extent.
    if (*ray > 2 * distance_to_edges(p.point - *ray * p.normal, edges)) continue;
    // And a ray measures a wall where it leaves by a face parallel to its
    // own, within 10°: one that leaves by a face turned further crosses a
    // junction (a fillet's ray runs down into the wall the fillet stands
    // on) or cuts a wall obliquely, longer than its thickness by 1 / cos of
    // the angle (at 15°, 3.5%: a voxel on a wall 30 voxels thick; at 10°,
    // 1.5%).
    if (glm::dot(p.normal, exit->normal) > kFacingCos) continue;
    // The filled voxel under the point, else the nearest one within a voxel.
    glm::i64vec3 at = voxel_of(p.point - 0.5 * h * p.normal);
    if (!inside(at)) {
      double best = std::numeric_limits<double>::infinity();
      const glm::i64vec3 c = voxel_of(p.point);
      for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const glm::i64vec3 v = c + glm::i64vec3(dx, dy, dz);
            const double d = glm::length(g.origin + (glm::dvec3(v) + 0.5) * h - p.point);
            if (inside(v) && d < best) best = d, at = v;
          }
      if (!inside(at)) continue;
    }
    const double t = map.at(at.x, at.y, at.z);
    errors.push_back(t - *ray / h);
    read.push_back(t * h);
    rays.push_back(*ray);
  }
  WallAgreement w;
  w.points = errors.size();
  if (errors.empty()) return w;
  const auto n = static_cast<double>(errors.size());
  w.within_1 = static_cast<double>(std::count_if(errors.begin(), errors.end(), [](double e) { return std::abs(e) <= 1.0; })) / n;
  w.within_1_5 = static_cast<double>(std::count_if(errors.begin(), errors.end(), [](double e) { return std::abs(e) <= 1.5; })) / n;
  w.p01 = percentile(errors, 0.01);
  w.p50 = percentile(errors, 0.50);
  w.p99 = percentile(errors, 0.99);
  w.min = *std::min_element(read.begin(), read.end());
  w.ray_min = *std::min_element(rays.begin(), rays.end());
  for (std::size_t i = 0; i < read.size(); ++i) w.mean += read[i] / n, w.ray_mean += rays[i] / n;
  return w;
}

VertexAgreement compare_vertices_with_rays(const Mesh& welded, const std::vector<float>& thickness, double h,
                                           std::size_t max_vertices) {
  const std::vector<Segment> edges = sharp_edges(welded, 30.0);
  // Area-weighted vertex normals, written here (not the analysis's).
  std::vector<glm::dvec3> normals(welded.vertices.size(), glm::dvec3(0.0));
  std::vector<std::uint32_t> triangle_of(welded.vertices.size(), 0);
  for (std::uint32_t t = 0; t < welded.triangles.size(); ++t) {
    const Triangle tri = triangle(welded, t);
    for (const std::uint32_t v : welded.triangles[t]) {
      normals[v] += glm::cross(tri.b - tri.a, tri.c - tri.a);
      triangle_of[v] = t;
    }
  }
  std::size_t ok = 0, n = 0;
  const std::size_t stride = std::max<std::size_t>(1, (welded.vertices.size() + max_vertices - 1) / std::max<std::size_t>(max_vertices, 1));
  for (std::size_t v = 0; v < welded.vertices.size(); v += stride) {
    if (glm::length(normals[v]) == 0) continue;
    const glm::dvec3 p(welded.vertices[v]);
    const double to_edge = distance_to_edges(p, edges);
    if (to_edge < 2 * h) continue;
    const SurfacePoint sp{p, glm::normalize(normals[v]), triangle_of[v]};
    const std::optional<RayHit> exit = ray_hit(welded, sp);
    if (!exit || exit->distance > 2 * to_edge ||
        exit->distance > 2 * distance_to_edges(p - exit->distance * sp.normal, edges) ||
        glm::dot(sp.normal, exit->normal) > kFacingCos)
      continue;
    ++n;
    if (std::abs(thickness[v] - exit->distance / h) <= 1.0) ++ok;
  }
  return {n, n ? static_cast<double>(ok) / static_cast<double>(n) : 0.0};
}

}  // namespace voxd::test
