#pragma once
// The feature transform of a binary volume: for every filled voxel, the
// nearest EMPTY voxel centre (Euclidean, in voxels), as the distance
// transform (voxd/analysis/distance_transform.h) measures it, but which one
// rather than how far. Everything outside the grid counts as empty, as
// there. Wall thickness needs it: the two surfaces a wall lies between are
// told apart by where each voxel's nearest empty voxel is.
//
// Not part of the engine's API (for wall thickness and its tests).
//
// Same separable method as the distance transform (Meijster et al. 2000),
// carrying the nearest site along instead of only its distance; integer
// arithmetic throughout, so the distance to the voxel given is exactly the
// distance transform's (ties may pick either voxel).
//
// Memory: one uint32 per voxel. Indices are of the grid padded by one empty
// layer on every side, so outside voxels have one too; grids whose padded
// voxel count exceeds 2^32 (about 1600^3) are refused.
#include <cstdint>

#include <glm/vec3.hpp>

#include "voxd/bit_volume.h"
#include "voxd/dense_volume.h"
#include "voxd/progress.h"

namespace voxd::detail {

// Indices of the grid padded by one layer on every side: voxel (x, y, z),
// -1 <= x <= nx, ... has index (x + 1) + px ((y + 1) + py (z + 1)).
struct PaddedIndex {
  std::int64_t px = 0, py = 0, pz = 0;
  explicit PaddedIndex(const Grid& grid)
      : px(grid.dims.x + 2), py(grid.dims.y + 2), pz(grid.dims.z + 2),
        inverse_px_(UINT64_MAX / static_cast<std::uint64_t>(px) + 1),
        inverse_py_(UINT64_MAX / static_cast<std::uint64_t>(py) + 1) {}
  std::uint32_t of(std::int64_t x, std::int64_t y, std::int64_t z) const {
    return static_cast<std::uint32_t>((x + 1) + px * ((y + 1) + py * (z + 1)));
  }
  // The decodes are the inner loops of the feature transforms and of wall
  // thickness, so they divide by multiplying: for 32-bit n and d,
  // floor(n / d) = (ceil(2^64 / d) * n) >> 64 exactly (Lemire, Kaser &
  // Kurz 2019), and every padded index fits in 32 bits (larger grids are
  // refused).
  // The padded row (y + 1) + py (z + 1) an index lies in.
  std::uint32_t row_of(std::uint32_t index) const { return divide(index, inverse_px_); }
  glm::i64vec3 at(std::uint32_t index) const {
    const std::uint32_t row = divide(index, inverse_px_), slab = divide(row, inverse_py_);
    return {static_cast<std::int64_t>(index) - static_cast<std::int64_t>(row) * px - 1,
            static_cast<std::int64_t>(row) - static_cast<std::int64_t>(slab) * py - 1,
            static_cast<std::int64_t>(slab) - 1};
  }

 private:
  static std::uint32_t divide(std::uint32_t n, std::uint64_t inverse) {
    return static_cast<std::uint32_t>((static_cast<unsigned __int128>(inverse) * n) >> 64);
  }
  std::uint64_t inverse_px_ = 0, inverse_py_ = 0;
};

// For a filled voxel, the padded index of its nearest empty voxel; for an
// empty one, its own. `threads` 0 = all cores; `control` may be null (then
// progress and cancellation are not reported). Throws Error(limit_exceeded)
// for a grid of more than 2^32 padded voxels.
DenseVolume<std::uint32_t> nearest_empty_voxels(const BitVolume& solid, int threads = 0,
                                                JobControl* control = nullptr, double progress_from = 0.0,
                                                double progress_to = 1.0);

// What nearest_marked_voxels gives a voxel when no voxel is marked.
inline constexpr std::uint32_t kNoNearestVoxel = 0xFFFFFFFFu;

// For every voxel, the padded index of the nearest MARKED voxel (set bit)
// inside the grid (itself if marked; outside the grid nothing is marked),
// or kNoNearestVoxel if none is, written over `out` (a volume of the same
// grid is reused as it is: wall thickness reuses its feature transform's,
// once done with it, rather than touch as much memory again). Wall
// thickness gives each voxel the wall of its nearest medial voxel with it.
// With `wanted` (same grid), only its set voxels are sure of their answer,
// the same one as without it; the others may hold any voxel (the last pass
// skips the lines where none is wanted: wall thickness wants the filled
// voxels only). Same method, limits and arguments as nearest_empty_voxels.
void nearest_marked_voxels(const BitVolume& marked, DenseVolume<std::uint32_t>& out,
                           const BitVolume* wanted = nullptr, int threads = 0, JobControl* control = nullptr,
                           double progress_from = 0.0, double progress_to = 1.0);

}  // namespace voxd::detail
