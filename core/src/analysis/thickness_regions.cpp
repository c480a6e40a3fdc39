// Connected thin / thick regions by flood fill: one scan in voxel order, an
// explicit stack (no recursion depth limit), a bit per voxel to mark visits.
// Sequential: the scan order is what makes the output deterministic, and the
// cost is a few passes over the voxels, small next to the thickness itself.
#include "voxd/analysis/thickness_regions.h"

#include <algorithm>
#include <unordered_map>

#include <glm/common.hpp>

namespace voxd {

std::vector<ThicknessRegion> find_thickness_regions(const DenseVolume<float>& thickness, ThicknessRegionKind kind,
                                                    float threshold_voxels, std::uint64_t min_voxels,
                                                    const std::vector<std::size_t>* probes,
                                                    std::vector<std::uint32_t>* probe_regions) {
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

  // The probed voxels, a bit each; the region each one's flood met it in
  // (by the order regions are met, -1 for none), by voxel.
  std::vector<std::uint64_t> probed;
  std::unordered_map<std::size_t, std::int64_t> met_in;
  if (probes) {
    probed.assign(visited.size(), 0);
    for (const std::size_t p : *probes)
      if (p < t.size()) probed[p >> 6] |= std::uint64_t{1} << (p & 63);
  }
  std::int64_t met = 0;  // regions met so far, kept or not
  std::vector<std::int64_t> kept_as;  // per region met: its place in `found`, or -1

  struct Found {
    ThicknessRegion region;
    std::size_t first;
    std::size_t order;  // its place in `found` before sorting
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
      if (!probed.empty() && (probed[idx >> 6] >> (idx & 63) & 1)) met_in[idx] = met;
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
    ++met;
    kept_as.push_back(r.voxel_count < min_voxels ? -1 : static_cast<std::int64_t>(found.size()));
    if (r.voxel_count < min_voxels) continue;
    r.centroid = sum / static_cast<double>(r.voxel_count);
    r.mean_thickness = static_cast<float>(thickness_sum / static_cast<double>(r.voxel_count));
    found.push_back({r, seed, found.size()});
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
  std::vector<std::uint32_t> rank_of_found(found.size());
  for (const Found& f : found) {
    rank_of_found[f.order] = static_cast<std::uint32_t>(regions.size());
    regions.push_back(f.region);
  }
  if (probes && probe_regions) {
    probe_regions->assign(probes->size(), 0);
    for (std::size_t i = 0; i < probes->size(); ++i) {
      const auto it = met_in.find((*probes)[i]);
      if (it == met_in.end()) continue;
      const std::int64_t place = kept_as[static_cast<std::size_t>(it->second)];
      if (place >= 0) (*probe_regions)[i] = rank_of_found[static_cast<std::size_t>(place)] + 1;
    }
  }
  return regions;
}

}  // namespace voxd
