// Peel depth against a brute-force city-block distance and an explicit
// erosion loop, with shapes whose layers are known; clean-up counts.
#include <cstdint>
#include <random>

#include <gtest/gtest.h>

#include "support/test_meshes.h"
#include "voxd/analysis/cleanup.h"
#include "voxd/analysis/components.h"
#include "voxd/analysis/skin_removal.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd {
namespace {

using test::unit_grid;

// Peeling as the paper describes it: remove every filled voxel with an empty
// face neighbour (or the grid's outside), layer after layer.
VolumeVector<std::uint16_t> erode_layers(const BitVolume& v) {
  const auto d = v.grid().dims;
  auto idx = [&](std::int64_t i, std::int64_t j, std::int64_t k) { return static_cast<std::size_t>(i + d.x * (j + d.y * k)); };
  std::vector<char> cur(static_cast<std::size_t>(d.x * d.y * d.z));
  for (std::int64_t k = 0; k < d.z; ++k)
    for (std::int64_t j = 0; j < d.y; ++j)
      for (std::int64_t i = 0; i < d.x; ++i) cur[idx(i, j, k)] = v.get(i, j, k);
  VolumeVector<std::uint16_t> layer(cur.size(), 0);
  for (std::uint16_t l = 1;; ++l) {
    std::vector<char> next = cur;
    bool any = false;
    for (std::int64_t k = 0; k < d.z; ++k)
      for (std::int64_t j = 0; j < d.y; ++j)
        for (std::int64_t i = 0; i < d.x; ++i) {
          if (!cur[idx(i, j, k)]) continue;
          const glm::i64vec3 nb[6] = {{i - 1, j, k}, {i + 1, j, k}, {i, j - 1, k}, {i, j + 1, k}, {i, j, k - 1}, {i, j, k + 1}};
          bool exposed = false;
          for (const auto& n : nb)
            exposed = exposed || n.x < 0 || n.y < 0 || n.z < 0 || n.x >= d.x || n.y >= d.y || n.z >= d.z || !cur[idx(n.x, n.y, n.z)];
          if (exposed) {
            next[idx(i, j, k)] = 0;
            layer[idx(i, j, k)] = l;
            any = true;
          }
        }
    if (!any) break;
    cur = std::move(next);
  }
  return layer;
}

// Euclidean peeling by its definition: the layer of a filled voxel is the
// smallest integer r with r^2 >= its squared distance to the nearest empty
// voxel centre (the grid's outside counting as empty, one layer out).
TEST(SkinRemoval, EuclideanPeelDepthIsTheCeilingOfTheDistanceToTheOutside) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 10; ++trial) {
    const glm::i64vec3 dims(static_cast<std::int64_t>(rng() % 30 + 1), static_cast<std::int64_t>(rng() % 14 + 1),
                            static_cast<std::int64_t>(rng() % 12 + 1));
    BitVolume v(unit_grid(dims));
    for (std::int64_t k = 0; k < dims.z; ++k)
      for (std::int64_t j = 0; j < dims.y; ++j)
        for (std::int64_t i = 0; i < dims.x; ++i) v.set(i, j, k, rng() % 10 != 0);
    const auto depth = peel_depth(v, 2, PeelMetric::euclidean);
    for (std::int64_t k = 0; k < dims.z; ++k)
      for (std::int64_t j = 0; j < dims.y; ++j)
        for (std::int64_t i = 0; i < dims.x; ++i) {
          if (!v.get(i, j, k)) {
            ASSERT_EQ(depth.at(i, j, k), 0);
            continue;
          }
          std::int64_t best = INT64_MAX;
          for (std::int64_t c = -1; c <= dims.z; ++c)
            for (std::int64_t b = -1; b <= dims.y; ++b)
              for (std::int64_t a = -1; a <= dims.x; ++a) {
                const bool outside = a < 0 || b < 0 || c < 0 || a >= dims.x || b >= dims.y || c >= dims.z;
                if (!outside && v.get(a, b, c)) continue;
                best = std::min(best, (a - i) * (a - i) + (b - j) * (b - j) + (c - k) * (c - k));
              }
          std::int64_t r = 0;
          while (r * r < best) ++r;
          ASSERT_EQ(depth.at(i, j, k), r) << i << "," << j << "," << k;
        }
  }
}

// On a wall at 45 degrees the 6-connected layers cut deeper steps than the
// wall is thick; Euclidean layers follow the true depth.
TEST(SkinRemoval, EuclideanLayersFollowASlantedWallFacesLayersDoNot) {
  const Grid g = unit_grid({40, 40, 3});
  BitVolume v(g);
  for (std::int64_t k = 0; k < 3; ++k)
    for (std::int64_t j = 0; j < 40; ++j)
      for (std::int64_t i = 0; i < 40; ++i)
        if (std::abs(i - j) <= 6) v.set(i, j, k, true);  // diagonal band ~9.2 voxels wide in x-y
  auto depth_at_centre = [&](PeelMetric m) {
    std::int64_t k = 1;  // the middle layer of 3: its z distance is 2
    return static_cast<int>(peel_depth(v, 1, m).at(20, 20, k));
  };
  // Distance from (20,20) to the nearest empty centre in-plane: (20,27) or
  // (27,20) at 7, or (23.5-ish) diagonally; z bounds it at 2 either way.
  EXPECT_EQ(depth_at_centre(PeelMetric::euclidean), 2);
  EXPECT_EQ(depth_at_centre(PeelMetric::faces), 2);
  const Grid g2 = unit_grid({40, 40, 40});
  BitVolume band(g2);
  for (std::int64_t k = 0; k < 40; ++k)
    for (std::int64_t j = 0; j < 40; ++j)
      for (std::int64_t i = 0; i < 40; ++i)
        if (std::abs(i - j) <= 6 && k > 0 && k < 39) band.set(i, j, k, true);
  const auto faces = peel_depth(band, 1, PeelMetric::faces);
  const auto euclid = peel_depth(band, 1, PeelMetric::euclidean);
  // Centre line of the band: 7 face steps to the outside along x or y, but
  // only 7 / sqrt(2) ~ 4.95 in straight distance to the nearest empty centre
  // (i - j = 7 at (23.5, 16.5)-like lattice points: (24,17) is at distance
  // sqrt(16 + 9) = 5 from (20,20)).
  EXPECT_EQ(faces.at(20, 20, 20), 7);
  EXPECT_EQ(euclid.at(20, 20, 20), 5);
  EXPECT_STREQ(to_string(PeelMetric::euclidean), "euclidean");
}

TEST(SkinRemoval, PeelDepthEqualsLayerByLayerErosionOnRandomVolumes) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 30; ++trial) {
    const glm::i64vec3 dims(static_cast<std::int64_t>(rng() % 80 + 1), static_cast<std::int64_t>(rng() % 20 + 1),
                            static_cast<std::int64_t>(rng() % 15 + 1));
    const BitVolume v = test::random_volume(dims, 0.6 + 0.39 * (rng() % 100) / 100.0, rng);
    const auto want = erode_layers(v);
    for (const int threads : {1, 3}) EXPECT_EQ(peel_depth(v, threads).values(), want) << "trial " << trial << " threads " << threads;
  }
}

// The summary's voxels a layer and deepest layer, against a plain count of
// the erosion's layers: random volumes whose z layers are not a multiple of
// 16 voxels, with empty stretches and deep ones, on 1 and 3 threads.
TEST(SkinRemoval, VoxelsPerLayerCountTheErosionsLayers) {
  std::mt19937 rng(23);
  for (int trial = 0; trial < 30; ++trial) {
    const glm::i64vec3 dims(static_cast<std::int64_t>(rng() % 70 + 1), static_cast<std::int64_t>(rng() % 20 + 1),
                            static_cast<std::int64_t>(rng() % 20 + 1));
    const BitVolume v = test::random_volume(dims, (trial % 3 == 0 ? 0.2 : 0.7) + 0.29 * (rng() % 100) / 100.0, rng);
    std::vector<std::uint64_t> want;
    for (const std::uint16_t layer : erode_layers(v)) {
      if (layer == 0) continue;
      if (layer > want.size()) want.resize(layer, 0);
      ++want[layer - 1u];
    }
    for (const int threads : {1, 3}) {
      const PeelSummary s = summarize_peeling(peel_depth(v, threads), threads);
      EXPECT_EQ(s.voxels_per_layer, want) << "trial " << trial << " threads " << threads;
      EXPECT_EQ(s.max_depth, want.size()) << "trial " << trial;
    }
  }
}

TEST(SkinRemoval, BoxLayersAreNestedShellsAndTheCoreIsTheHotSpot) {
  // An 11 x 9 x 7 block of voxels: 4 layers, the last a 5 x 3 x 1 core.
  const Grid g = unit_grid({15, 13, 11});
  const BitVolume v = voxelize(test::make_box({2, 2, 2}, {13, 11, 9}), g, {});
  ASSERT_EQ(v.count(), 11u * 9u * 7u);
  const auto depth = peel_depth(v);
  const PeelSummary s = summarize_peeling(depth);
  ASSERT_EQ(s.max_depth, 4u);
  auto shell = [](int a, int b, int c) { return static_cast<std::uint64_t>(a * b * c - std::max(a - 2, 0) * std::max(b - 2, 0) * std::max(c - 2, 0)); };
  EXPECT_EQ(s.voxels_per_layer, (std::vector<std::uint64_t>{shell(11, 9, 7), shell(9, 7, 5), shell(7, 5, 3), 5u * 3u * 1u}));
  ASSERT_EQ(s.innermost.size(), 1u);
  EXPECT_EQ(s.innermost[0].voxels, 15u);
  EXPECT_EQ(s.innermost[0].bbox_min, glm::i64vec3(5, 5, 5));
  EXPECT_EQ(s.innermost[0].bbox_max, glm::i64vec3(9, 7, 5));
  EXPECT_EQ(peeled(depth, 2).count(), 7u * 5u * 3u);
  EXPECT_EQ(peeled(depth, 4).count(), 0u);
}

TEST(SkinRemoval, TwoHotSpotsOfEqualDepthAreBothReported) {
  const Grid g = unit_grid({30, 9, 9});
  const Mesh m = test::concat({test::make_box({1, 1, 1}, {8, 8, 8}), test::make_box({20, 1, 1}, {27, 8, 8}),
                               test::make_box({8, 4, 4}, {20, 5, 5})});  // joined by a thin bar
  const PeelSummary s = summarize_peeling(peel_depth(voxelize(m, g, {})));
  // Each 7-voxel cube's centre is 4 layers deep; the bar shields the centre's
  // neighbour on its side, which is 4 deep too.
  EXPECT_EQ(s.max_depth, 4u);
  ASSERT_EQ(s.innermost.size(), 2u);
  EXPECT_EQ(s.innermost[0].voxels, 2u);
  EXPECT_EQ(s.innermost[0].bbox_min, glm::i64vec3(4, 4, 4));
  EXPECT_EQ(s.innermost[0].bbox_max, glm::i64vec3(5, 4, 4));
  EXPECT_EQ(s.innermost[1].voxels, 2u);
  EXPECT_EQ(s.innermost[1].bbox_min, glm::i64vec3(22, 4, 4));
  EXPECT_EQ(s.innermost[1].bbox_max, glm::i64vec3(23, 4, 4));
}

// The innermost regions are found scanning only the z layers that reach
// the deepest depth: the same regions as from the whole volume peeled to
// it, on random volumes (hot spots scattered over many layers) and on two
// equally deep blocks at different heights, each deep over several layers.
TEST(SkinRemoval, InnermostRegionsAreThoseOfTheWholeVolumePeeledToTheDeepest) {
  const auto expect_same = [](const std::vector<VoxelRegion>& a, const std::vector<VoxelRegion>& b) {
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t r = 0; r < a.size(); ++r) {
      EXPECT_EQ(a[r].voxels, b[r].voxels) << r;
      EXPECT_EQ(a[r].bbox_min, b[r].bbox_min) << r;
      EXPECT_EQ(a[r].bbox_max, b[r].bbox_max) << r;
      EXPECT_EQ(a[r].centroid, b[r].centroid) << r;
    }
  };
  std::mt19937 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    const glm::i64vec3 dims(static_cast<std::int64_t>(rng() % 40 + 3), static_cast<std::int64_t>(rng() % 20 + 3),
                            static_cast<std::int64_t>(rng() % 30 + 3));
    const BitVolume v = test::random_volume(dims, 0.75 + 0.24 * (rng() % 100) / 100.0, rng);
    const auto depth = peel_depth(v, 2);
    const PeelSummary s = summarize_peeling(depth, 2);
    if (s.max_depth == 0) continue;
    SCOPED_TRACE("trial " + std::to_string(trial));
    expect_same(s.innermost, find_components(peeled(depth, s.max_depth - 1)).parts);
  }
  // Two 7 x 7 x 11 blocks, one at z 1..11 and one at z 14..24: each core is
  // 4 deep over 5 layers.
  const Grid g = unit_grid({20, 9, 26});
  const Mesh m = test::concat({test::make_box({1, 1, 1}, {8, 8, 12}), test::make_box({11, 1, 14}, {18, 8, 25})});
  const auto depth = peel_depth(voxelize(m, g, {}));
  const PeelSummary s = summarize_peeling(depth);
  EXPECT_EQ(s.max_depth, 4u);
  ASSERT_EQ(s.innermost.size(), 2u);
  EXPECT_EQ(s.innermost[0].voxels, 5u);
  EXPECT_EQ(s.innermost[0].bbox_min, glm::i64vec3(4, 4, 4));
  EXPECT_EQ(s.innermost[0].bbox_max, glm::i64vec3(4, 4, 8));
  EXPECT_EQ(s.innermost[1].bbox_min, glm::i64vec3(14, 4, 17));
  EXPECT_EQ(s.innermost[1].bbox_max, glm::i64vec3(14, 4, 21));
  expect_same(s.innermost, find_components(peeled(depth, 3)).parts);
}

TEST(Cleanup, RemovesIsolatedVoxelsLinesAndOptionallySheets) {
  const Grid g = unit_grid({70, 20, 20});
  auto make = [&] {
    BitVolume v(g);
    v.set(2, 2, 2, true);                               // isolated
    for (int i = 10; i < 20; ++i) v.set(i, 5, 5, true); // a line of 10 along x: every voxel thin along y and z
    for (int j = 0; j < 8; ++j)                         // an 8 x 8 sheet one voxel thick along z
      for (int i = 60; i < 68; ++i) v.set(i, j, 10, true);
    for (int k = 12; k < 16; ++k)                       // a solid 4 x 4 x 4 block
      for (int j = 12; j < 16; ++j)
        for (int i = 62; i < 66; ++i) v.set(i, j, k, true);
    return v;
  };
  BitVolume a = make();
  const std::uint64_t before = a.count();
  const CleanupReport r = clean_up(a, {});
  EXPECT_EQ(r.isolated, 1u);
  EXPECT_EQ(r.lines, 10u);
  EXPECT_EQ(r.sheets, 0u);
  EXPECT_EQ(a.count(), before - 11u);
  EXPECT_TRUE(a.get(60, 0, 10));  // sheets kept unless asked for
  // With sheets: every sheet voxel (rim included: a rim voxel has a filled
  // neighbour on one side along x or y) is thin along z only.
  BitVolume b = make();
  const CleanupReport all = clean_up(b, {true, true, true});
  EXPECT_EQ(all.isolated, 1u);
  EXPECT_EQ(all.lines, 10u);
  EXPECT_EQ(all.sheets, 64u);
  EXPECT_EQ(b.count(), 64u);  // only the block is left
  EXPECT_TRUE(b.get(63, 13, 13));
  // The pass is simultaneous: a 2-voxel stub is not eaten from its end inwards.
  BitVolume c(g);
  c.set(30, 10, 10, true);
  c.set(31, 10, 10, true);
  EXPECT_EQ(clean_up(c, {}).lines, 2u);
}

}  // namespace
}  // namespace voxd
