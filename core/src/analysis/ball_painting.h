#pragma once
// Painting balls largest first: every filled voxel takes the value of the
// first ball, in the order handed out, whose lattice ball contains its
// centre (|v - c|^2 <= r2). Handed out largest radius first, that is the
// largest ball containing the voxel. Local thickness (every filled voxel a
// centre, its diameter as the value) and wall thickness (the centres of the
// wall's medial surface, the wall's thickness as the value) both paint this
// way; see voxd/analysis/local_thickness.h for how it is made fast without
// approximating.
#include <cstdint>
#include <functional>

#include "analysis/progress_span.h"
#include "voxd/bit_volume.h"
#include "voxd/dense_volume.h"

namespace voxd::detail {

struct Ball {
  std::uint64_t index = 0;  // linear voxel index of the centre
  std::uint32_t r2 = 0;     // squared radius, in voxels
  float value = 0.0f;       // what the ball paints
};

// Hands out balls by non-increasing r2; false when there is none left.
using BallSource = std::function<bool(Ball&)>;

// Whether the ball (x, y, z, r2) lies inside a ball handed out earlier, so
// it would paint nothing: skipped without walking it.
using BallContained = std::function<bool(std::int64_t x, std::int64_t y, std::int64_t z, std::int64_t r2)>;

struct BallPaintingTuning {
  std::int64_t sparse_from = -1;              // leftovers that start the sparse phase; -1: max(4096, voxels / 256)
  std::int64_t reach_rebuild_queries = 4096;  // tree walks before the reach bound may be rebuilt
};

// Paints `out` (same grid as `solid`, 0 where unpainted). Returns the filled
// voxels no ball reached, which keep their value in `out`. `progress` goes
// from 0 to 1 as the filled voxels get their values.
std::int64_t paint_balls_largest_first(const BitVolume& solid, DenseVolume<float>& out, const BallSource& balls,
                                       const BallContained& contained, const BallPaintingTuning& tuning, int threads,
                                       const ProgressSpan& progress);

// floor(sqrt(n)), exact for every n < 2^52.
std::int64_t isqrt(std::int64_t n);
// ceil(sqrt(n)).
std::int64_t ceil_sqrt(std::int64_t n);

}  // namespace voxd::detail
