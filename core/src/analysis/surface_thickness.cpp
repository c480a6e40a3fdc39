#include "voxd/analysis/surface_thickness.h"

#include <cmath>
#include <limits>

#include <glm/geometric.hpp>

namespace voxd {

std::vector<glm::vec3> vertex_normals(const Mesh& mesh) {
  std::vector<glm::dvec3> sum(mesh.vertices.size(), glm::dvec3(0.0));
  for (const auto& t : mesh.triangles) {
    const glm::dvec3 a(mesh.vertices[t[0]]), b(mesh.vertices[t[1]]), c(mesh.vertices[t[2]]);
    const glm::dvec3 n = glm::cross(b - a, c - a);  // twice the area, along the normal
    for (const std::uint32_t v : t) sum[v] += n;
  }
  std::vector<glm::vec3> out(sum.size(), glm::vec3(0.0f));
  for (std::size_t i = 0; i < sum.size(); ++i) {
    const double len = glm::length(sum[i]);
    if (len > 0) out[i] = glm::vec3(sum[i] / len);
  }
  return out;
}

namespace {

constexpr std::size_t kNoVoxel = std::numeric_limits<std::size_t>::max();

// The filled voxel under vertex `p` (model units) with unit normal `n`: the
// one half a voxel inward, else the filled one whose centre is nearest `p`
// among the 27 around it.
std::size_t voxel_under(const DenseVolume<float>& map, const glm::dvec3& p, const glm::dvec3& n) {
  const Grid& g = map.grid();
  const double h = g.voxel_size;
  auto voxel_of = [&](const glm::dvec3& q) { return glm::i64vec3(glm::floor((q - g.origin) / h)); };
  auto in_grid = [&](const glm::i64vec3& v) {
    return v.x >= 0 && v.y >= 0 && v.z >= 0 && v.x < g.dims.x && v.y < g.dims.y && v.z < g.dims.z;
  };
  const glm::i64vec3 under = voxel_of(p - 0.5 * h * n);
  if (in_grid(under) && map.at(under.x, under.y, under.z) > 0) return map.index(under.x, under.y, under.z);
  const glm::i64vec3 c = voxel_of(p);
  std::size_t best = kNoVoxel;
  double best_d2 = std::numeric_limits<double>::infinity();
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const glm::i64vec3 v = c + glm::i64vec3(dx, dy, dz);
        if (!in_grid(v) || !(map.at(v.x, v.y, v.z) > 0)) continue;
        const glm::dvec3 d = g.origin + (glm::dvec3(v) + 0.5) * h - p;
        const double d2 = glm::dot(d, d);
        if (d2 < best_d2) best_d2 = d2, best = map.index(v.x, v.y, v.z);
      }
  return best;
}

}  // namespace

SurfaceThickness surface_thickness(const Mesh& mesh, const DenseVolume<float>& map,
                                   std::optional<float> thin_below_voxels, std::uint64_t min_region_voxels) {
  const std::vector<glm::vec3> normals = vertex_normals(mesh);
  SurfaceThickness out;
  out.thickness.assign(mesh.vertices.size(), 0.0f);
  std::vector<std::size_t> voxels(mesh.vertices.size(), kNoVoxel);
  const auto& values = map.values();
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    voxels[i] = voxel_under(map, glm::dvec3(mesh.vertices[i]), glm::dvec3(normals[i]));
    if (voxels[i] == kNoVoxel) {
      ++out.unresolved;
      continue;
    }
    out.thickness[i] = values[voxels[i]];
  }
  if (thin_below_voxels)
    out.thin_regions =
        find_thickness_regions(map, ThicknessRegionKind::thin, *thin_below_voxels, min_region_voxels, &voxels, &out.thin_region);
  return out;
}

}  // namespace voxd
