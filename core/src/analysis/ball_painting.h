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

#include <glm/vec3.hpp>

#include "analysis/progress_span.h"
#include "voxd/bit_volume.h"
#include "voxd/dense_volume.h"

namespace voxd::detail {

struct Ball {
  std::uint64_t index = 0;  // linear voxel index of the centre
  std::uint32_t r2 = 0;     // squared radius, in voxels
  float value = 0.0f;       // what the ball paints
  std::uint32_t tag = 0;    // the source's own, for BallAccepts
};

// Hands out balls by non-increasing r2; false when there is none left.
using BallSource = std::function<bool(Ball&)>;

// Whether the ball (x, y, z, r2) lies inside a ball handed out earlier, so
// it would paint nothing: skipped without walking it.
using BallContained = std::function<bool(std::int64_t x, std::int64_t y, std::int64_t z, std::int64_t r2)>;

// Whether the ball may paint the filled voxel (x, y, z) inside it; a voxel it
// refuses stays for later balls. Empty: every voxel inside is painted.
using BallAccepts = std::function<bool(const Ball& ball, std::int64_t x, std::int64_t y, std::int64_t z)>;

struct BallPaintingTuning {
  std::int64_t sparse_from = -1;              // leftovers that start the sparse phase; -1: max(4096, voxels / 256)
  std::int64_t reach_rebuild_queries = 4096;  // tree walks before the reach bound may be rebuilt
};

// Paints `out` (same grid as `solid`, 0 where unpainted). Returns the filled
// voxels no ball reached, which keep their value in `out`. `progress` goes
// from 0 to 1 as the filled voxels get their values. With `accepts`, a
// ball skipped by `contained` is taken to accept nothing its container
// refused: the skip stays a bound on work, not an exact test.
std::int64_t paint_balls_largest_first(const BitVolume& solid, DenseVolume<float>& out, const BallSource& balls,
                                       const BallContained& contained, const BallPaintingTuning& tuning, int threads,
                                       const ProgressSpan& progress, const BallAccepts& accepts = {});

// floor(sqrt(n)), exact for every n < 2^52.
std::int64_t isqrt(std::int64_t n);
// ceil(sqrt(n)).
std::int64_t ceil_sqrt(std::int64_t n);

// Whether the ball at (x, y, z) with squared radius r2 lies inside the ball of
// one of its 26 neighbours. The ball at c + e (squared radius R') contains it
// when sqrt(R') >= sqrt(r2) + |e|, i.e. R' >= r2 + |e|^2 + 2 sqrt(r2 |e|^2)
// (the continuous containment, sufficient for the lattice balls). Such a ball
// is larger, so it was painted earlier and already covered every voxel of
// this one: skipping it is exact. On walls along the grid axes this drops
// nearly every ball but the mid-plane's; on tilted walls few, as the radius
// seldom grows by a whole step per neighbour.
// `r2_at(i, j, k)` is the squared radius of the ball centred at voxel
// (i, j, k), 0 where there is none; `d` the grid's dims.
template <typename RadiusAt>
bool inside_a_neighbour(const glm::i64vec3& d, std::int64_t x, std::int64_t y, std::int64_t z, std::int64_t r2,
                        const RadiusAt& r2_at) {
  std::int64_t need[4] = {0, 0, 0, 0};
  for (std::int64_t e2 = 1; e2 <= 3; ++e2) need[e2] = r2 + e2 + ceil_sqrt(4 * r2 * e2);
  for (int dz = -1; dz <= 1; ++dz) {
    const std::int64_t k = z + dz;
    if (k < 0 || k >= d.z) continue;
    for (int dy = -1; dy <= 1; ++dy) {
      const std::int64_t j = y + dy;
      if (j < 0 || j >= d.y) continue;
      for (int dx = -1; dx <= 1; ++dx) {
        const std::int64_t i = x + dx;
        const int e2 = dx * dx + dy * dy + dz * dz;
        if (e2 == 0 || i < 0 || i >= d.x) continue;
        if (r2_at(i, j, k) >= need[e2]) return true;
      }
    }
  }
  return false;
}

}  // namespace voxd::detail
