// The exact distance transform against a brute-force reference: for every
// filled voxel, the minimum over all empty voxel centres (the grid padded with
// one empty layer stands for the empty outside) of the squared distance.
#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <random>

#include "support/test_meshes.h"
#include "voxd/analysis/distance_transform.h"
#include "voxd/error.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd {
namespace {

using test::unit_grid;

std::uint32_t brute_force_d2(const BitVolume& v, std::int64_t i, std::int64_t j, std::int64_t k) {
  const auto d = v.grid().dims;
  if (!v.get(i, j, k)) return 0;
  std::int64_t best = std::numeric_limits<std::int64_t>::max();
  for (std::int64_t z = -1; z <= d.z; ++z)
    for (std::int64_t y = -1; y <= d.y; ++y)
      for (std::int64_t x = -1; x <= d.x; ++x) {
        const bool inside = x >= 0 && y >= 0 && z >= 0 && x < d.x && y < d.y && z < d.z;
        if (inside && v.get(x, y, z)) continue;
        const std::int64_t dd = (x - i) * (x - i) + (y - j) * (y - j) + (z - k) * (z - k);
        best = std::min(best, dd);
      }
  return static_cast<std::uint32_t>(best);
}

void expect_matches_brute_force(const BitVolume& v, int threads = 0) {
  const DenseVolume<std::uint32_t> edt = squared_distance_transform(v, threads);
  const auto d = v.grid().dims;
  ASSERT_EQ(edt.grid().dims, d);
  std::int64_t mismatches = 0;
  for (std::int64_t k = 0; k < d.z; ++k)
    for (std::int64_t j = 0; j < d.y; ++j)
      for (std::int64_t i = 0; i < d.x; ++i) {
        const std::uint32_t want = brute_force_d2(v, i, j, k);
        if (edt.at(i, j, k) != want && ++mismatches <= 5) {
          ADD_FAILURE() << "voxel (" << i << "," << j << "," << k << "): got " << edt.at(i, j, k) << ", want "
                        << want;
        }
      }
  EXPECT_EQ(mismatches, 0);
}

BitVolume random_volume(const Grid& g, double density, std::uint32_t seed) {
  BitVolume v(g);
  std::mt19937 rng(seed);
  std::bernoulli_distribution fill(density);
  for (std::int64_t k = 0; k < g.dims.z; ++k)
    for (std::int64_t j = 0; j < g.dims.y; ++j)
      for (std::int64_t i = 0; i < g.dims.x; ++i) v.set(i, j, k, fill(rng));
  return v;
}

TEST(DistanceTransform, MatchesBruteForceOnRandomVolumes) {
  const double densities[] = {0.3, 0.7, 0.9, 0.97, 1.0};
  std::uint32_t seed = 1;
  for (double density : densities) {
    for (int rep = 0; rep < 3; ++rep, ++seed) {
      SCOPED_TRACE(testing::Message() << "density " << density << " seed " << seed);
      expect_matches_brute_force(random_volume(unit_grid(23, 17, 11), density, seed));
    }
  }
}

TEST(DistanceTransform, MatchesBruteForceAcrossWordsAndOddShapes) {
  // x spans three 64-bit words (runs across word boundaries), and degenerate
  // 1-voxel axes.
  expect_matches_brute_force(random_volume(unit_grid(131, 7, 5), 0.95, 7));
  expect_matches_brute_force(random_volume(unit_grid(64, 9, 3), 0.99, 8));
  expect_matches_brute_force(random_volume(unit_grid(1, 19, 13), 0.9, 9));
  expect_matches_brute_force(random_volume(unit_grid(17, 1, 1), 0.9, 10));
  expect_matches_brute_force(random_volume(unit_grid(5, 3, 29), 0.95, 11));
}

TEST(DistanceTransform, SameResultOnOneThreadAndMany) {
  const BitVolume v = random_volume(unit_grid(45, 33, 27), 0.97, 12);
  const auto one = squared_distance_transform(v, 1);
  const auto many = squared_distance_transform(v, 4);
  EXPECT_EQ(one.values(), many.values());
}

TEST(DistanceTransform, VoxelizedSphereMatchesBruteForce) {
  Grid g;
  g.origin = {-12.0, -12.0, -12.0};
  g.dims = {24, 24, 24};
  const BitVolume v = voxelize(test::make_icosphere({0.3, -0.2, 0.1}, 10.0, 4), g, {});
  ASSERT_GT(v.count(), 3000u);
  expect_matches_brute_force(v);
}

TEST(DistanceTransform, FullGridIsDistanceToTheOutside) {
  // Everything filled: the nearest empty centre is outside the grid, so the
  // distance is (1 + distance to the nearest face)^2.
  Grid g = unit_grid(9, 7, 5);
  BitVolume v(g);
  for (std::int64_t k = 0; k < 5; ++k)
    for (std::int64_t j = 0; j < 7; ++j)
      for (std::int64_t i = 0; i < 9; ++i) v.set(i, j, k, true);
  const auto edt = squared_distance_transform(v);
  for (std::int64_t k = 0; k < 5; ++k)
    for (std::int64_t j = 0; j < 7; ++j)
      for (std::int64_t i = 0; i < 9; ++i) {
        const std::int64_t d = 1 + std::min({i, 8 - i, j, 6 - j, k, 4 - k});
        ASSERT_EQ(edt.at(i, j, k), static_cast<std::uint32_t>(d * d)) << i << "," << j << "," << k;
      }
  EXPECT_EQ(edt.at(4, 3, 2), 9u);
}

TEST(DistanceTransform, DiagonalNeighbourIsNotTheNearest) {
  // One empty voxel in a filled block: distances are exact squared Euclidean
  // (2 and 3 for the diagonal neighbours), not city-block or chessboard.
  Grid g = unit_grid(11, 11, 11);
  BitVolume v(g);
  for (std::int64_t k = 0; k < 11; ++k)
    for (std::int64_t j = 0; j < 11; ++j)
      for (std::int64_t i = 0; i < 11; ++i) v.set(i, j, k, true);
  v.set(5, 5, 5, false);
  const auto edt = squared_distance_transform(v);
  EXPECT_EQ(edt.at(5, 5, 5), 0u);
  EXPECT_EQ(edt.at(6, 5, 5), 1u);
  EXPECT_EQ(edt.at(6, 6, 5), 2u);
  EXPECT_EQ(edt.at(6, 6, 6), 3u);
  EXPECT_EQ(edt.at(7, 6, 6), 6u);
  EXPECT_EQ(edt.at(3, 5, 5), 4u);
  EXPECT_EQ(edt.at(2, 5, 5), 9u);  // the outside is at distance 3 too
}

TEST(DistanceTransform, EmptyVolumeIsAllZero) {
  const BitVolume v(unit_grid(70, 3, 2));
  const auto edt = squared_distance_transform(v);
  for (std::uint32_t d : edt.values()) ASSERT_EQ(d, 0u);
}

TEST(DistanceTransform, HonoursCancellation) {
  const BitVolume v = random_volume(unit_grid(40, 40, 40), 0.9, 13);
  JobControl control;
  control.request_cancel();
  try {
    (void)squared_distance_transform(v, 2, &control);
    FAIL() << "expected Error(cancelled)";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::cancelled);
  }
}

TEST(DistanceTransform, ReportsProgressToTheEnd) {
  const BitVolume v = random_volume(unit_grid(40, 40, 40), 0.9, 14);
  JobControl control;
  (void)squared_distance_transform(v, 2, &control);
  EXPECT_DOUBLE_EQ(control.progress(), 1.0);
}

}  // namespace
}  // namespace voxd
