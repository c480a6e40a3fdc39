// Peel depth against a brute-force city-block distance and an explicit
// erosion loop, with shapes whose layers are known; clean-up counts.
#include <random>

#include <gtest/gtest.h>

#include "support/test_meshes.h"
#include "voxd/cleanup.h"
#include "voxd/skin_removal.h"
#include "voxd/voxelize.h"

namespace voxd {
namespace {

Grid unit_grid(glm::i64vec3 dims) {
  Grid g;
  g.voxel_size = 1.0;
  g.dims = dims;
  return g;
}

// Peeling as the paper describes it: remove every filled voxel with an empty
// face neighbour (or the grid's outside), layer after layer.
std::vector<std::uint16_t> erode_layers(const BitVolume& v) {
  const auto d = v.grid().dims;
  auto idx = [&](std::int64_t i, std::int64_t j, std::int64_t k) { return static_cast<std::size_t>(i + d.x * (j + d.y * k)); };
  std::vector<char> cur(static_cast<std::size_t>(d.x * d.y * d.z));
  for (std::int64_t k = 0; k < d.z; ++k)
    for (std::int64_t j = 0; j < d.y; ++j)
      for (std::int64_t i = 0; i < d.x; ++i) cur[idx(i, j, k)] = v.get(i, j, k);
  std::vector<std::uint16_t> layer(cur.size(), 0);
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

TEST(SkinRemoval, PeelDepthEqualsLayerByLayerErosionOnRandomVolumes) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 30; ++trial) {
    const glm::i64vec3 dims(static_cast<std::int64_t>(rng() % 80 + 1), static_cast<std::int64_t>(rng() % 20 + 1),
                            static_cast<std::int64_t>(rng() % 15 + 1));
    BitVolume v(unit_grid(dims));
    std::bernoulli_distribution fill(0.6 + 0.39 * (rng() % 100) / 100.0);
    for (std::int64_t k = 0; k < dims.z; ++k)
      for (std::int64_t j = 0; j < dims.y; ++j)
        for (std::int64_t i = 0; i < dims.x; ++i) v.set(i, j, k, fill(rng));
    EXPECT_EQ(peel_depth(v).values(), erode_layers(v)) << "trial " << trial;
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
