// Parts and voids against shapes with known answers and against a
// brute-force flood fill on random volumes, for both connectivities.
#include <algorithm>
#include <cstdlib>
#include <queue>
#include <random>
#include <string>
#include <tuple>
#include <utility>

#include <glm/common.hpp>
#include <gtest/gtest.h>

#include "support/test_meshes.h"
#include "voxd/analysis/components.h"
#include "voxd/byte_sink.h"
#include "voxd/encode/rle_slabs.h"
#include "voxd/encode/volume_format.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd {
namespace {

using test::unit_grid;

// Reference: BFS over voxels. Solid 26-connected; empty 6-connected, with
// regions touching the border dropped. Each region as its voxel count, box
// and centroid, in the labeller's order (largest first, then by box).
struct Found {
  std::uint64_t voxels;
  glm::i64vec3 lo, hi;
  glm::dvec3 centroid;
  bool operator==(const Found&) const = default;
};

std::vector<Found> brute_force_regions(const BitVolume& v, bool empty_phase) {
  const auto d = v.grid().dims;
  std::vector<char> seen(static_cast<std::size_t>(d.x * d.y * d.z), 0);
  auto idx = [&](std::int64_t i, std::int64_t j, std::int64_t k) { return static_cast<std::size_t>(i + d.x * (j + d.y * k)); };
  std::vector<Found> found;
  for (std::int64_t k = 0; k < d.z; ++k)
    for (std::int64_t j = 0; j < d.y; ++j)
      for (std::int64_t i = 0; i < d.x; ++i) {
        if (seen[idx(i, j, k)] || v.get(i, j, k) == empty_phase) continue;
        std::uint64_t n = 0;
        glm::i64vec3 lo{i, j, k}, hi{i, j, k}, sum{0};
        bool border = false;
        std::queue<glm::i64vec3> q;
        q.push({i, j, k});
        seen[idx(i, j, k)] = 1;
        while (!q.empty()) {
          const auto p = q.front();
          q.pop();
          ++n;
          sum += p;
          lo = glm::min(lo, p);
          hi = glm::max(hi, p);
          if (p.x == 0 || p.y == 0 || p.z == 0 || p.x == d.x - 1 || p.y == d.y - 1 || p.z == d.z - 1) border = true;
          for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
              for (int dx = -1; dx <= 1; ++dx) {
                const int manhattan = std::abs(dx) + std::abs(dy) + std::abs(dz);
                if (manhattan == 0 || (empty_phase && manhattan != 1)) continue;
                const glm::i64vec3 q2 = p + glm::i64vec3(dx, dy, dz);
                if (q2.x < 0 || q2.y < 0 || q2.z < 0 || q2.x >= d.x || q2.y >= d.y || q2.z >= d.z) continue;
                if (seen[idx(q2.x, q2.y, q2.z)] || v.get(q2.x, q2.y, q2.z) == empty_phase) continue;
                seen[idx(q2.x, q2.y, q2.z)] = 1;
                q.push(q2);
              }
        }
        if (!(empty_phase && border))
          found.push_back({n, lo, hi, glm::dvec3(sum) / static_cast<double>(n)});
      }
  std::sort(found.begin(), found.end(), [](const Found& a, const Found& b) {
    if (a.voxels != b.voxels) return a.voxels > b.voxels;
    return std::tuple(a.lo.z, a.lo.y, a.lo.x, a.hi.z, a.hi.y, a.hi.x, a.centroid.z, a.centroid.y, a.centroid.x) <
           std::tuple(b.lo.z, b.lo.y, b.lo.x, b.hi.z, b.hi.y, b.hi.x, b.centroid.z, b.centroid.y, b.centroid.x);
  });
  return found;
}

// The labeller's regions as the reference gives them (ties in count and box,
// which the labeller leaves in any order, ordered by centroid).
std::vector<Found> found_of(const std::vector<VoxelRegion>& regions) {
  std::vector<Found> f;
  for (const auto& r : regions) f.push_back({r.voxels, r.bbox_min, r.bbox_max, r.centroid});
  std::stable_sort(f.begin(), f.end(), [](const Found& a, const Found& b) {
    if (a.voxels != b.voxels) return a.voxels > b.voxels;
    return std::tuple(a.lo.z, a.lo.y, a.lo.x, a.hi.z, a.hi.y, a.hi.x, a.centroid.z, a.centroid.y, a.centroid.x) <
           std::tuple(b.lo.z, b.lo.y, b.lo.x, b.hi.z, b.hi.y, b.hi.x, b.centroid.z, b.centroid.y, b.centroid.x);
  });
  return f;
}

TEST(Components, TwoDisjointBoxesAreTwoPartsWithExactCountsAndBoxes) {
  const Grid g = unit_grid({30, 20, 20});
  const Mesh m = test::concat({test::make_box({1, 1, 1}, {5, 6, 7}), test::make_box({10, 2, 3}, {20, 12, 8})});
  const ComponentReport r = find_components(voxelize(m, g, {}));
  ASSERT_EQ(r.parts.size(), 2u);
  EXPECT_EQ(r.parts[0].voxels, 10u * 10u * 5u);
  EXPECT_EQ(r.parts[0].bbox_min, glm::i64vec3(10, 2, 3));
  EXPECT_EQ(r.parts[0].bbox_max, glm::i64vec3(19, 11, 7));
  EXPECT_EQ(r.parts[0].centroid, glm::dvec3(14.5, 6.5, 5.0));
  EXPECT_EQ(r.parts[1].voxels, 4u * 5u * 6u);
  EXPECT_EQ(region_centroid_model(r.parts[1], g), glm::dvec3(3.0, 3.5, 4.0));
  EXPECT_TRUE(r.voids.empty());
}

TEST(Components, HollowBoxHasOneVoidTheSizeOfItsCavity) {
  const Grid g = unit_grid({12, 12, 12});
  const Mesh m = test::concat({test::make_box({1, 1, 1}, {11, 11, 11}), test::flipped(test::make_box({3, 4, 5}, {8, 9, 9}))});
  const ComponentReport r = find_components(voxelize(m, g, {}));
  ASSERT_EQ(r.parts.size(), 1u);
  ASSERT_EQ(r.voids.size(), 1u);
  EXPECT_EQ(r.voids[0].voxels, 5u * 5u * 4u);
  EXPECT_EQ(r.voids[0].bbox_min, glm::i64vec3(3, 4, 5));
  EXPECT_EQ(r.voids[0].bbox_max, glm::i64vec3(7, 8, 8));
  EXPECT_EQ(r.parts[0].voxels, 1000u - 100u);
}

TEST(Components, ACavityOpenToTheOutsideIsNoVoid) {
  const Grid g = unit_grid({12, 12, 12});
  // A cup: the cavity reaches the top face of the block.
  BitVolume v(g);
  for (int k = 1; k < 11; ++k)
    for (int j = 1; j < 11; ++j)
      for (int i = 1; i < 11; ++i) v.set(i, j, k, !(i >= 3 && i < 8 && j >= 3 && j < 8 && k >= 4));
  EXPECT_TRUE(find_components(v).voids.empty());
  // Closing its mouth traps it.
  for (int j = 3; j < 8; ++j)
    for (int i = 3; i < 8; ++i) v.set(i, j, 10, true);
  const ComponentReport r = find_components(v);
  ASSERT_EQ(r.voids.size(), 1u);
  EXPECT_EQ(r.voids[0].voxels, 5u * 5u * 6u);
}

TEST(Components, DiagonalContactJoinsPartsButDoesNotOpenAVoid) {
  const Grid g = unit_grid({6, 6, 6});
  BitVolume v(g);
  v.set(1, 1, 1, true);
  v.set(2, 2, 2, true);  // touches the first only by a corner: one part
  EXPECT_EQ(find_components(v).parts.size(), 1u);
  // A 3x3x3 shell with its centre empty and one edge voxel missing: the
  // centre reaches the missing voxel only diagonally, so it stays enclosed.
  BitVolume s(g);
  for (int k = 1; k < 4; ++k)
    for (int j = 1; j < 4; ++j)
      for (int i = 1; i < 4; ++i) s.set(i, j, k, !(i == 2 && j == 2 && k == 2));
  s.set(1, 1, 2, false);  // edge voxel (face-adjacent to outside, edge-adjacent to centre)
  const ComponentReport r = find_components(s);
  ASSERT_EQ(r.voids.size(), 1u);
  EXPECT_EQ(r.voids[0].voxels, 1u);
}

TEST(Components, RandomVolumesMatchABruteForceFloodFill) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 40; ++trial) {
    const glm::i64vec3 dims(static_cast<std::int64_t>(rng() % 70 + 1), static_cast<std::int64_t>(rng() % 13 + 1),
                            static_cast<std::int64_t>(rng() % 11 + 1));
    const double density = 0.15 + 0.7 * (rng() % 100) / 100.0;
    const BitVolume v = test::random_volume(dims, density, rng);
    const std::vector<Found> parts = brute_force_regions(v, false), voids = brute_force_regions(v, true);
    // In memory on 1, 2 or 3 threads, and from the volume's stored runs in
    // slabs of 1 and 4 layers: every region's count, box and centroid.
    std::vector<std::pair<std::string, ComponentReport>> reports;
    for (int threads : {1, 2, 3}) reports.emplace_back("threads " + std::to_string(threads), find_components(v, threads));
    VectorSink rle;
    write_rle(v, rle);
    for (std::int64_t layers : {1, 4}) {
      ComponentLabeller labeller(v.grid(), 2);
      read_rle_run_slabs(rle.data, layers, [&](std::int64_t k0, const RunSlab& slab) { labeller.add(k0, slab); });
      reports.emplace_back("runs in slabs of " + std::to_string(layers), labeller.finish());
    }
    for (const auto& [how, r] : reports) {
      EXPECT_EQ(found_of(r.parts), parts) << "trial " << trial << ", " << how;
      EXPECT_EQ(found_of(r.voids), voids) << "trial " << trial << ", " << how;
      std::uint64_t solid = 0;
      for (const auto& p : r.parts) solid += p.voxels;
      EXPECT_EQ(solid, v.count());
    }
  }
}

// Unsorted, as the labeller orders them: its order must not depend on the
// thread count either.
std::vector<Found> as_listed(const std::vector<VoxelRegion>& regions) {
  std::vector<Found> f;
  for (const auto& r : regions) f.push_back({r.voxels, r.bbox_min, r.bbox_max, r.centroid});
  return f;
}

// With more threads each phase's layers are cut into runs of layers
// labelled apart and then joined: deep random volumes, where parts, voids
// and the outside cross the cuts in every way (a region ending in one run
// of layers and joined again in a later one; a void that the outside
// reaches only through a later run), against the flood fill and against a
// single thread, in the same order. Also from the stored runs, slab by
// slab, where each slab is cut again.
TEST(Components, LayersLabelledApartAndJoinedAreTheRegionsOfOneThreadInTheSameOrder) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 30; ++trial) {
    const glm::i64vec3 dims(static_cast<std::int64_t>(rng() % 40 + 1), static_cast<std::int64_t>(rng() % 12 + 1),
                            static_cast<std::int64_t>(rng() % 57 + 8));
    const double density = 0.2 + 0.6 * (rng() % 100) / 100.0;
    const BitVolume v = test::random_volume(dims, density, rng);
    const std::vector<Found> parts = brute_force_regions(v, false), voids = brute_force_regions(v, true);
    const ComponentReport one = find_components(v, 1);
    ASSERT_EQ(found_of(one.parts), parts) << "trial " << trial;
    ASSERT_EQ(found_of(one.voids), voids) << "trial " << trial;
    std::vector<std::pair<std::string, ComponentReport>> reports;
    for (int threads : {4, 6, 9, 16, 64}) reports.emplace_back("threads " + std::to_string(threads), find_components(v, threads));
    VectorSink rle;
    write_rle(v, rle);
    for (std::int64_t layers : {5, 17}) {
      ComponentLabeller labeller(v.grid(), 8);
      read_rle_run_slabs(rle.data, layers, [&](std::int64_t k0, const RunSlab& slab) { labeller.add(k0, slab); });
      reports.emplace_back("runs in slabs of " + std::to_string(layers) + " on 8 threads", labeller.finish());
    }
    for (const auto& [how, r] : reports) {
      EXPECT_EQ(as_listed(r.parts), as_listed(one.parts)) << "trial " << trial << ", " << how;
      EXPECT_EQ(as_listed(r.voids), as_listed(one.voids)) << "trial " << trial << ", " << how;
    }
  }
}

// Shapes made to cross the cuts (40 layers, 16 threads: runs of 5 layers):
// an arch whose two legs meet only at its top, a cavity closed only by its
// lid several runs up, and a shaft from a closed cavity that reaches the
// outside only at the grid's last layer.
TEST(Components, ArchesLidsAndShaftsAcrossTheCutsAreOneRegionEach) {
  const glm::i64vec3 dims(12, 12, 40);
  // An arch: two legs from layer 0 to 29, joined by a bridge at 30..33.
  BitVolume arch(unit_grid(dims));
  for (std::int64_t k = 0; k < 34; ++k)
    for (std::int64_t j = 4; j < 8; ++j)
      for (std::int64_t i = 0; i < 12; ++i)
        if (k >= 30 || i < 3 || i >= 9) arch.set(i, j, k, true);
  // A closed box, walls 1 thick, over layers 2..37: one void of 8 x 8 x 34.
  BitVolume box(unit_grid(dims));
  for (std::int64_t k = 2; k < 38; ++k)
    for (std::int64_t j = 1; j < 11; ++j)
      for (std::int64_t i = 1; i < 11; ++i)
        if (k == 2 || k == 37 || j == 1 || j == 10 || i == 1 || i == 10) box.set(i, j, k, true);
  // The same box with a shaft from its cavity up through the lid and on to
  // the grid's top layer: no void.
  BitVolume shaft = box.clone();
  for (std::int64_t k = 37; k < 40; ++k)
    for (std::int64_t j = 3; j < 6; ++j)
      for (std::int64_t i = 3; i < 6; ++i) {
        shaft.set(i, j, k, false);
        if (k > 37) {
          for (std::int64_t dj = -1; dj <= 1; ++dj)
            for (std::int64_t di = -1; di <= 1; ++di)
              if (std::abs(dj) + std::abs(di) > 0 && !(j + dj >= 3 && j + dj < 6 && i + di >= 3 && i + di < 6))
                shaft.set(i + di, j + dj, k, true);
        }
      }
  for (int threads : {1, 16}) {
    SCOPED_TRACE("threads " + std::to_string(threads));
    const ComponentReport a = find_components(arch, threads);
    ASSERT_EQ(a.parts.size(), 1u);
    EXPECT_EQ(a.parts[0].voxels, arch.count());
    EXPECT_EQ(a.voids.size(), 0u);
    const ComponentReport b = find_components(box, threads);
    ASSERT_EQ(b.parts.size(), 1u);
    ASSERT_EQ(b.voids.size(), 1u);
    EXPECT_EQ(b.voids[0].voxels, 8u * 8u * 34u);
    EXPECT_EQ(b.voids[0].bbox_min, glm::i64vec3(2, 2, 3));
    EXPECT_EQ(b.voids[0].bbox_max, glm::i64vec3(9, 9, 36));
    const ComponentReport c = find_components(shaft, threads);
    ASSERT_EQ(c.parts.size(), 1u);
    EXPECT_EQ(c.voids.size(), 0u);
  }
}

}  // namespace
}  // namespace voxd
