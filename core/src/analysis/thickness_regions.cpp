// Connected thin / thick regions by flood fill: one scan in voxel order, an
// explicit stack (no recursion depth limit), a bit per voxel to mark visits.
// Sequential: the scan order is what makes the output deterministic, and the
// cost is a few passes over the voxels, small next to the thickness itself.
#include "voxd/analysis/thickness_regions.h"

#include <algorithm>

#include <glm/common.hpp>

namespace voxd {

std::vector<ThicknessRegion> find_thickness_regions(const DenseVolume<float>& thickness, ThicknessRegionKind kind,
                                                    float threshold_voxels, std::uint64_t min_voxels) {
  const auto d = thickness.grid().dims;
  const auto& t = thickness.values();
  auto selected = [&](std::size_t idx) {
    const float v = t[idx];
    return kind == ThicknessRegionKind::thin ? (v > 0.0f && v < threshold_voxels) : (v > 0.0f && v > threshold_voxels);
  };
  std::vector<std::uint64_t> visited((t.size() + 63) / 64, 0);
  auto test_and_mark = [&](std::size_t idx) {
    std::uint64_t& w = visited[idx >> 6];
    const std::uint64_t bit = std::uint64_t{1} << (idx & 63);
    const bool was = (w & bit) != 0;
    w |= bit;
    return was;
  };

  struct Found {
    ThicknessRegion region;
    std::size_t first;
  };
  std::vector<Found> found;
  std::vector<std::size_t> stack;
  const auto sx = static_cast<std::size_t>(d.x);
  const auto sxy = static_cast<std::size_t>(d.x * d.y);
  for (std::size_t seed = 0; seed < t.size(); ++seed) {
    if (!selected(seed) || test_and_mark(seed)) continue;
    ThicknessRegion r;
    r.bbox_min = {d.x, d.y, d.z};
    r.bbox_max = {-1, -1, -1};
    r.extreme_thickness = t[seed];
    glm::dvec3 sum{0.0};
    double thickness_sum = 0.0;
    stack.assign(1, seed);
    while (!stack.empty()) {
      const std::size_t idx = stack.back();
      stack.pop_back();
      const auto i = static_cast<std::int64_t>(idx % sx);
      const auto j = static_cast<std::int64_t>((idx / sx) % static_cast<std::size_t>(d.y));
      const auto k = static_cast<std::int64_t>(idx / sxy);
      ++r.voxel_count;
      thickness_sum += t[idx];
      sum += glm::dvec3(static_cast<double>(i), static_cast<double>(j), static_cast<double>(k));
      r.bbox_min = glm::min(r.bbox_min, glm::i64vec3(i, j, k));
      r.bbox_max = glm::max(r.bbox_max, glm::i64vec3(i, j, k));
      r.extreme_thickness = kind == ThicknessRegionKind::thin ? std::min(r.extreme_thickness, t[idx])
                                                              : std::max(r.extreme_thickness, t[idx]);
      for (std::int64_t dz = -1; dz <= 1; ++dz) {
        const std::int64_t z = k + dz;
        if (z < 0 || z >= d.z) continue;
        for (std::int64_t dy = -1; dy <= 1; ++dy) {
          const std::int64_t y = j + dy;
          if (y < 0 || y >= d.y) continue;
          for (std::int64_t dx = -1; dx <= 1; ++dx) {
            const std::int64_t x = i + dx;
            if (x < 0 || x >= d.x) continue;
            const std::size_t n = thickness.index(x, y, z);
            if (selected(n) && !test_and_mark(n)) stack.push_back(n);
          }
        }
      }
    }
    if (r.voxel_count < min_voxels) continue;
    r.centroid = sum / static_cast<double>(r.voxel_count);
    r.mean_thickness = static_cast<float>(thickness_sum / static_cast<double>(r.voxel_count));
    found.push_back({r, seed});
  }
  // Most severe first: the thinnest (thickest) extreme, then the larger
  // region, then scan order.
  std::stable_sort(found.begin(), found.end(), [kind](const Found& a, const Found& b) {
    if (a.region.extreme_thickness != b.region.extreme_thickness)
      return kind == ThicknessRegionKind::thin ? a.region.extreme_thickness < b.region.extreme_thickness
                                               : a.region.extreme_thickness > b.region.extreme_thickness;
    if (a.region.voxel_count != b.region.voxel_count) return a.region.voxel_count > b.region.voxel_count;
    return a.first < b.first;
  });
  std::vector<ThicknessRegion> regions;
  regions.reserve(found.size());
  for (const Found& f : found) regions.push_back(f.region);
  return regions;
}

}  // namespace voxd
