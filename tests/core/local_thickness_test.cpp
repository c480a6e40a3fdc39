// Local thickness against its definition (brute force over every inscribed
// ball) and against shapes whose wall thickness is known, plus statistics,
// the error statement and the thin / thick region finder.
#include <gtest/gtest.h>

#include <glm/common.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <utility>
#include <vector>

#include "support/test_meshes.h"
#include "voxd/analysis/distance_transform.h"
#include "voxd/error.h"
#include "voxd/analysis/local_thickness.h"
#include "voxd/detail/local_thickness_tuning.h"
#include "voxd/analysis/thickness_regions.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd {
namespace {

using test::unit_grid;

// thickness(v) = max { 2 sqrt(d2(c)) : c filled, |v - c|^2 <= d2(c) }, by
// trying every centre for every voxel. d2 from the distance transform, which
// distance_transform_test checks against its own brute force.
DenseVolume<float> brute_force_thickness(const BitVolume& v) {
  const auto edt = squared_distance_transform(v, 1);
  const auto d = v.grid().dims;
  DenseVolume<float> out(v.grid(), 0.0f);
  struct Centre {
    std::int64_t i, j, k, d2;
    float value;
  };
  std::vector<Centre> centres;
  for (std::int64_t k = 0; k < d.z; ++k)
    for (std::int64_t j = 0; j < d.y; ++j)
      for (std::int64_t i = 0; i < d.x; ++i)
        if (edt.at(i, j, k) > 0) {
          const std::int64_t d2 = edt.at(i, j, k);
          centres.push_back({i, j, k, d2, static_cast<float>(2.0 * std::sqrt(static_cast<double>(d2)))});
        }
  for (const Centre& p : centres) {  // p: the voxel
    float best = 0.0f;
    for (const Centre& c : centres) {
      const std::int64_t dd = (p.i - c.i) * (p.i - c.i) + (p.j - c.j) * (p.j - c.j) + (p.k - c.k) * (p.k - c.k);
      if (dd <= c.d2) best = std::max(best, c.value);
    }
    out.at(p.i, p.j, p.k) = best;
  }
  return out;
}

void expect_equals(const DenseVolume<float>& got, const DenseVolume<float>& want) {
  const auto d = want.grid().dims;
  std::int64_t mismatches = 0;
  for (std::int64_t k = 0; k < d.z; ++k)
    for (std::int64_t j = 0; j < d.y; ++j)
      for (std::int64_t i = 0; i < d.x; ++i)
        if (got.at(i, j, k) != want.at(i, j, k) && ++mismatches <= 5) {
          ADD_FAILURE() << "voxel (" << i << "," << j << "," << k << "): got " << got.at(i, j, k) << ", want "
                        << want.at(i, j, k);
        }
  EXPECT_EQ(mismatches, 0);
}

void expect_equals_brute_force(const BitVolume& v, int threads = 0) {
  expect_equals(local_thickness(v, threads), brute_force_thickness(v));
}

// Union of random balls and boxes, with a sprinkle of flipped voxels: thick
// and thin parts, curved and flat walls, isolated voxels and pinholes.
BitVolume random_shape(const Grid& g, std::uint32_t seed) {
  BitVolume v(g);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(0.0, static_cast<double>(g.dims.x));
  std::uniform_real_distribution<double> uy(0.0, static_cast<double>(g.dims.y));
  std::uniform_real_distribution<double> uz(0.0, static_cast<double>(g.dims.z));
  std::uniform_real_distribution<double> radius(1.5, 8.0);
  for (int n = 0; n < 6; ++n) {
    const glm::dvec3 c{ux(rng), uy(rng), uz(rng)};
    const double r = radius(rng);
    const bool ball = n % 2 == 0;
    for (std::int64_t k = 0; k < g.dims.z; ++k)
      for (std::int64_t j = 0; j < g.dims.y; ++j)
        for (std::int64_t i = 0; i < g.dims.x; ++i) {
          const glm::dvec3 p{i + 0.5, j + 0.5, k + 0.5};
          const glm::dvec3 q = p - c;
          const bool in = ball ? (q.x * q.x + q.y * q.y + q.z * q.z < r * r)
                               : (std::abs(q.x) < r && std::abs(q.y) < r / 3 && std::abs(q.z) < r * 0.8);
          if (in) v.set(i, j, k, true);
        }
  }
  std::bernoulli_distribution flip(0.02);
  for (std::int64_t k = 0; k < g.dims.z; ++k)
    for (std::int64_t j = 0; j < g.dims.y; ++j)
      for (std::int64_t i = 0; i < g.dims.x; ++i)
        if (flip(rng)) v.set(i, j, k, !v.get(i, j, k));
  return v;
}

TEST(LocalThickness, EqualsBruteForceOnRandomShapes) {
  for (std::uint32_t seed = 1; seed <= 6; ++seed) {
    SCOPED_TRACE(testing::Message() << "seed " << seed);
    const BitVolume v = random_shape(unit_grid(25, 21, 17), seed);
    ASSERT_GT(v.count(), 500u);
    expect_equals_brute_force(v, seed % 2 == 0 ? 1 : 3);
  }
}

TEST(LocalThickness, EqualsBruteForceOnVoxelizedTorusAndSphere) {
  expect_equals_brute_force(
      voxelize(test::make_torus({0.2, -0.3, 0.1}, 8.0, 3.3, 48, 24), unit_grid(26, 26, 12, {-13, -13, -6}), {}));
  expect_equals_brute_force(
      voxelize(test::make_icosphere({0.4, 0.1, -0.2}, 9.2, 4), unit_grid(21, 21, 21, {-10.5, -10.5, -10.5}), {}));
}

// The painting has a dense phase (rows), a sparse phase (kd-tree of the
// leftovers behind a coarse reach bound) and gathers the centres range by
// range. The defaults hardly use some of these paths on test-sized volumes, so
// each is forced here, alone and mixed, and must give the brute-force answer.
TEST(LocalThickness, EveryPaintingPathEqualsBruteForce) {
  struct Path {
    const char* name;
    detail::LocalThicknessTuning tuning;
  };
  const Path paths[] = {
      {"dense phase only", {0, 0, 4096}},
      {"sparse phase only, bound rebuilt after every walk", {INT64_MAX, 0, 1}},
      {"sparse phase only, bound never rebuilt", {INT64_MAX, 0, INT64_MAX}},
      {"one centre per gathered range", {-1, 1, 4096}},
      {"switch mid-way, small ranges, frequent rebuilds", {1500, 97, 3}},
  };
  std::vector<BitVolume> shapes;
  for (std::uint32_t seed = 11; seed <= 13; ++seed) shapes.push_back(random_shape(unit_grid(31, 27, 23), seed));
  shapes.push_back(
      voxelize(test::make_torus({0.2, -0.3, 0.1}, 9.0, 4.1, 48, 24), unit_grid(30, 30, 12, {-15, -15, -6}), {}));
  for (std::size_t s = 0; s < shapes.size(); ++s) {
    const DenseVolume<float> want = brute_force_thickness(shapes[s]);
    for (const Path& p : paths) {
      SCOPED_TRACE(testing::Message() << "shape " << s << ", " << p.name);
      expect_equals(local_thickness(shapes[s], 2, nullptr, p.tuning), want);
    }
  }
}

TEST(LocalThickness, PlatesReportTheirThickness) {
  for (int n : {4, 6, 10}) {
    SCOPED_TRACE(testing::Message() << "plate " << n << " voxels");
    const std::int64_t side = 60;
    const Grid g = unit_grid(side, side, n + 6);
    const BitVolume v = voxelize(test::make_box({1, 1, 3}, {side - 1.0, side - 1.0, 3.0 + n}), g, {});
    const auto t = local_thickness(v);
    int checked = 0;
    for (std::int64_t j = 1 + n; j < side - 1 - n; ++j)
      for (std::int64_t i = 1 + n; i < side - 1 - n; ++i)
        for (std::int64_t k = 0; k < g.dims.z; ++k) {
          const bool filled = k >= 3 && k < 3 + n;
          ASSERT_EQ(v.get(i, j, k), filled);
          // Even thickness: exactly n, every voxel across the wall.
          ASSERT_EQ(t.at(i, j, k), filled ? static_cast<float>(n) : 0.0f) << i << "," << j << "," << k;
          ++checked;
        }
    EXPECT_GT(checked, 1000);
  }
}

TEST(LocalThickness, OddPlateReportsOneMore) {
  // The documented convention: ball centres on voxel centres, radius to the
  // first empty centre, so 5 voxels report 2 * 3 = 6.
  const Grid g = unit_grid(40, 40, 11);
  const BitVolume v = voxelize(test::make_box({1, 1, 3}, {39, 39, 8}), g, {});
  const auto t = local_thickness(v);
  for (std::int64_t k = 3; k < 8; ++k) EXPECT_EQ(t.at(20, 20, k), 6.0f);
}

TEST(LocalThickness, HollowBoxReportsItsWallThickness) {
  for (int w : {3, 4, 6}) {
    SCOPED_TRACE(testing::Message() << "wall " << w);
    // Closed shell: outer box and the inner box turned inside out.
    const glm::dvec3 lo{2, 2, 2}, hi{46, 40, 36};
    const Mesh shell = test::concat({test::make_box(lo, hi), test::flipped(test::make_box(lo + double(w), hi - double(w)))});
    const BitVolume v = voxelize(shell, unit_grid(48, 42, 38), {});
    const auto t = local_thickness(v);
    const float want = static_cast<float>(w % 2 == 0 ? w : w + 1);
    // The middle of each wall, far from the edges where two walls meet (and
    // larger balls fit in the corner).
    int checked = 0;
    for (std::int64_t a = 2 + 2 * w; a < 34 - 2 * w; ++a)
      for (std::int64_t b = 2 + 2 * w; b < 34 - 2 * w; ++b)
        for (std::int64_t c = 0; c < w; ++c) {
          ASSERT_EQ(t.at(2 + c, a, b), want);    // x = lo wall
          ASSERT_EQ(t.at(45 - c, a, b), want);   // x = hi wall
          ASSERT_EQ(t.at(a, 2 + c, b), want);    // y = lo wall
          ASSERT_EQ(t.at(a, b, 35 - c), want);   // z = hi wall
          ASSERT_EQ(t.at(a, 2 + w, b), 0.0f);    // the cavity
          checked += 4;
        }
    EXPECT_GT(checked, 500);
    EXPECT_LE(std::abs(want - static_cast<float>(w)), 1.0f);
  }
}

// A tube of wall thickness T (voxel units, walls between radii 14 and 14 + T
// around the grid's centre line, 36 layers long): every wall voxel farther
// than T from the open ends reports T within the stated error bound, and the
// wall's middle reports T exactly or one more nearly everywhere. (Near the
// ends the square rim is a convex edge: there the largest ball containing a
// voxel is smaller by definition, as at any edge of a part.)
TEST(LocalThickness, TubeWallReportsItsThickness) {
  for (int wall : {4, 6, 9}) {
    SCOPED_TRACE(testing::Message() << "wall " << wall);
    const double ri = 14.0, ro = ri + wall;
    const std::int64_t n = static_cast<std::int64_t>(2 * ro) + 4, first = 2, last = 37;
    const Grid g = unit_grid(n, n, last + 3);
    BitVolume v(g);
    const double c = static_cast<double>(n) / 2.0;
    auto radius = [&](std::int64_t i, std::int64_t j) {
      const double dx = i + 0.5 - c, dy = j + 0.5 - c;
      return std::sqrt(dx * dx + dy * dy);
    };
    for (std::int64_t k = first; k <= last; ++k)
      for (std::int64_t j = 0; j < n; ++j)
        for (std::int64_t i = 0; i < n; ++i)
          if (radius(i, j) > ri && radius(i, j) <= ro) v.set(i, j, k, true);
    const auto t = local_thickness(v);
    const ThicknessErrorBound bound = thickness_error_bound();
    std::uint64_t checked = 0, mid_exact = 0, mid = 0;
    for (std::int64_t k = 0; k < g.dims.z; ++k)
      for (std::int64_t j = 0; j < n; ++j)
        for (std::int64_t i = 0; i < n; ++i) {
          const float got = t.at(i, j, k);
          if (!v.get(i, j, k)) {
            ASSERT_EQ(got, 0.0f);
            continue;
          }
          ASSERT_GT(got, 0.0f);
          if (k < first + wall || k > last - wall) continue;  // the rims' convex edges
          ++checked;
          ASSERT_GE(got, wall - bound.below_voxels) << i << "," << j << "," << k;
          ASSERT_LE(got, wall + bound.above_voxels) << i << "," << j << "," << k;
          if (std::abs(radius(i, j) - (ri + ro) / 2) < 0.5) {
            ++mid;
            mid_exact += got >= wall - 0.5f && got <= wall + 1.5f;
          }
        }
    EXPECT_GT(checked, 1000u);
    ASSERT_GT(mid, 50u);
    EXPECT_GE(static_cast<double>(mid_exact) / static_cast<double>(mid), 0.9) << mid_exact << " of " << mid;
  }
}

TEST(LocalThickness, SphereCentreIsTheDiameter) {
  const double R = 10.3;
  const BitVolume v = voxelize(test::make_icosphere({0, 0, 0}, R, 4), unit_grid(25, 25, 25, {-12.5, -12.5, -12.5}), {});
  const auto t = local_thickness(v);
  EXPECT_NEAR(t.at(12, 12, 12), 2 * R, 1.0);
  // The central ball reaches the nearest empty centre, so it holds every
  // filled voxel: the whole sphere reports its value.
  const ThicknessStatistics st = thickness_statistics(t, 10);
  EXPECT_EQ(st.max, t.at(12, 12, 12));
  EXPECT_EQ(st.min, st.max);
  EXPECT_EQ(st.histogram.front(), v.count());
}

TEST(LocalThickness, SameResultOnOneThreadAndMany) {
  const BitVolume v = random_shape(unit_grid(70, 40, 50), 99);
  EXPECT_EQ(local_thickness(v, 1).values(), local_thickness(v, 4).values());
}

TEST(LocalThickness, HonoursCancellationAndReportsProgress) {
  const BitVolume v = random_shape(unit_grid(30, 30, 30), 5);
  JobControl done;
  (void)local_thickness(v, 2, &done);
  EXPECT_DOUBLE_EQ(done.progress(), 1.0);
  JobControl cancelled;
  cancelled.request_cancel();
  try {
    (void)local_thickness(v, 2, &cancelled);
    FAIL() << "expected Error(cancelled)";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::cancelled);
  }
}

TEST(ThicknessStatistics, HandComputedValues) {
  DenseVolume<float> t(unit_grid(5, 1, 1), 0.0f);
  t.at(1, 0, 0) = 2;
  t.at(2, 0, 0) = 2;
  t.at(3, 0, 0) = 4;
  t.at(4, 0, 0) = 6;
  const ThicknessStatistics st = thickness_statistics(t, 2);
  EXPECT_EQ(st.voxel_count, 4u);
  EXPECT_DOUBLE_EQ(st.mean, 3.5);
  EXPECT_DOUBLE_EQ(st.std_dev, std::sqrt(2.75));
  EXPECT_EQ(st.min, 2.0);
  EXPECT_EQ(st.max, 6.0);
  EXPECT_EQ(st.histogram, (std::vector<std::uint64_t>{2, 2}));  // [2,4): 2, 2; [4,6]: 4, 6
  EXPECT_DOUBLE_EQ(st.bin_width(), 2.0);

  const ThicknessStatistics one = thickness_statistics(DenseVolume<float>(unit_grid(3, 1, 1), 5.0f), 4);
  EXPECT_EQ(one.histogram, (std::vector<std::uint64_t>{3, 0, 0, 0}));
  EXPECT_EQ(one.std_dev, 0.0);
  EXPECT_TRUE(thickness_statistics(DenseVolume<float>(unit_grid(3, 1, 1), 0.0f), 4).histogram.empty());
  EXPECT_THROW(thickness_statistics(t, 0), Error);
}

TEST(ThicknessStatistics, MatchesAFreshComputationOnAShape) {
  const auto t = local_thickness(random_shape(unit_grid(30, 24, 20), 3));
  const int bins = 7;
  const ThicknessStatistics st = thickness_statistics(t, bins);
  double sum = 0, lo = 1e9, hi = 0;
  std::uint64_t n = 0;
  for (float v : t.values())
    if (v > 0) sum += v, ++n, lo = std::min<double>(lo, v), hi = std::max<double>(hi, v);
  const double mean = sum / static_cast<double>(n);
  double ss = 0;
  std::vector<std::uint64_t> hist(bins, 0);
  for (float v : t.values())
    if (v > 0) {
      ss += (v - mean) * (v - mean);
      int b = 0;
      while (b + 1 < bins && v >= lo + (hi - lo) * (b + 1) / bins) ++b;
      ++hist[static_cast<std::size_t>(b)];
    }
  EXPECT_EQ(st.voxel_count, n);
  EXPECT_NEAR(st.mean, mean, 1e-9);
  EXPECT_NEAR(st.std_dev, std::sqrt(ss / static_cast<double>(n)), 1e-9);
  EXPECT_EQ(st.min, lo);
  EXPECT_EQ(st.max, hi);
  EXPECT_EQ(st.histogram, hist);
  EXPECT_GT(hi, lo);
  // The same doubles on any number of threads.
  for (const int threads : {1, 2, 3, 8}) {
    const ThicknessStatistics other = thickness_statistics(t, bins, threads);
    EXPECT_EQ(other.mean, st.mean) << threads;
    EXPECT_EQ(other.std_dev, st.std_dev) << threads;
    EXPECT_EQ(other.histogram, st.histogram) << threads;
  }
}

TEST(ThicknessErrorBound, StatesVoxelsAndModelUnits) {
  const ThicknessErrorBound b = thickness_error_bound();
  EXPECT_EQ(b.below_voxels, 1.0);
  EXPECT_EQ(b.above_voxels, 2.0);
  const std::string s = thickness_error_statement(0.1);
  EXPECT_NE(s.find("-1 to +2 voxels (-0.1 to +0.2 model units)"), std::string::npos) << s;
}

// A 20-voxel block with a fin 2 voxels thick (y), 10 high (z) sticking out 12
// voxels along x, overlapping the block (winding number: a union of shells).
struct FinAndBlock {
  BitVolume solid;
  DenseVolume<float> thickness;
};
FinAndBlock fin_and_block() {
  const Mesh m = test::concat({test::make_box({4, 4, 4}, {24, 24, 24}), test::make_box({20, 10, 10}, {36, 12, 20})});
  VoxelizeOptions o;
  o.inside = InsideTest::winding;
  BitVolume v = voxelize(m, unit_grid(40, 28, 28), o);
  DenseVolume<float> t = local_thickness(v);
  return {std::move(v), std::move(t)};
}

TEST(ThicknessRegions, FindsExactlyTheThinFin) {
  const FinAndBlock s = fin_and_block();
  const auto regions = find_thickness_regions(s.thickness, ThicknessRegionKind::thin, 3.0f, 10);
  ASSERT_EQ(regions.size(), 1u);
  const ThicknessRegion& r = regions[0];
  // The fin's far part; next to the block, larger balls from the block reach
  // into the fin's first voxel or two.
  EXPECT_EQ(r.bbox_max, glm::i64vec3(35, 11, 19));
  EXPECT_EQ(r.bbox_min.y, 10);
  EXPECT_EQ(r.bbox_min.z, 10);
  EXPECT_GE(r.bbox_min.x, 24);
  EXPECT_LE(r.bbox_min.x, 26);
  const std::int64_t length = 36 - r.bbox_min.x;
  EXPECT_EQ(r.voxel_count, static_cast<std::uint64_t>(length * 2 * 10));
  EXPECT_EQ(r.extreme_thickness, 2.0f);
  EXPECT_DOUBLE_EQ(r.centroid.x, (r.bbox_min.x + 35) / 2.0);
  EXPECT_DOUBLE_EQ(r.centroid.y, 10.5);
  EXPECT_DOUBLE_EQ(r.centroid.z, 14.5);
  // Every voxel of the box the region spans is in it, and is thin.
  for (std::int64_t k = 10; k <= 19; ++k)
    for (std::int64_t j = 10; j <= 11; ++j)
      for (std::int64_t i = r.bbox_min.x; i <= 35; ++i) {
        ASSERT_TRUE(s.solid.get(i, j, k));
        ASSERT_LT(s.thickness.at(i, j, k), 3.0f);
      }
  // A larger minimum size drops it.
  EXPECT_TRUE(find_thickness_regions(s.thickness, ThicknessRegionKind::thin, 3.0f, r.voxel_count + 1).empty());
}

TEST(ThicknessRegions, ThickRegionIsTheBlockCore) {
  const FinAndBlock s = fin_and_block();
  const auto regions = find_thickness_regions(s.thickness, ThicknessRegionKind::thick, 19.0f, 1);
  ASSERT_EQ(regions.size(), 1u);
  const ThicknessRegion& r = regions[0];
  // The block is 20 voxels (4..23). Only the 8 central voxels (13 or 14 on
  // every axis) are 10 from the outside, the next distances are at most 9, so
  // thickness > 19 is exactly the union of those 8 balls of radius 10.
  std::uint64_t want = 0;
  for (std::int64_t k = 4; k <= 23; ++k)
    for (std::int64_t j = 4; j <= 23; ++j)
      for (std::int64_t i = 4; i <= 23; ++i) {
        auto d = [](std::int64_t a) { return std::min((a - 13) * (a - 13), (a - 14) * (a - 14)); };
        if (d(i) + d(j) + d(k) <= 100) ++want;
      }
  EXPECT_EQ(r.voxel_count, want);
  EXPECT_EQ(r.extreme_thickness, 20.0f);
  EXPECT_EQ(r.bbox_min, glm::i64vec3(4, 4, 4));
  EXPECT_EQ(r.bbox_max, glm::i64vec3(23, 23, 23));
  EXPECT_DOUBLE_EQ(r.centroid.x, 13.5);  // symmetric about the block centre
  EXPECT_DOUBLE_EQ(r.centroid.y, 13.5);
  EXPECT_DOUBLE_EQ(r.centroid.z, 13.5);
}

TEST(ThicknessRegions, OrderIsSeverityThenSizeThenPosition) {
  // Thin bars: A, 8 voxels of 2; B, 12 voxels of 2 and 2.5 in turn; C, 5
  // voxels of 2, then a thick voxel, then 2 voxels of 1.
  DenseVolume<float> t(unit_grid(20, 10, 3), 0.0f);
  for (std::int64_t i = 0; i < 8; ++i) t.at(i, 1, 1) = 2;
  for (std::int64_t i = 0; i < 12; ++i) t.at(i, 5, 1) = i % 2 ? 2.5f : 2.0f;
  for (std::int64_t i = 10; i < 15; ++i) t.at(i, 1, 1) = 2;
  t.at(15, 1, 1) = 8;
  t.at(16, 1, 1) = t.at(17, 1, 1) = 1;
  const auto r = find_thickness_regions(t, ThicknessRegionKind::thin, 3.0f, 2);
  ASSERT_EQ(r.size(), 4u);
  // The thinnest first, then equal minima largest first, then scan order.
  EXPECT_EQ(r[0].bbox_min, glm::i64vec3(16, 1, 1));
  EXPECT_EQ(r[0].extreme_thickness, 1.0f);
  EXPECT_EQ(r[1].voxel_count, 12u);
  EXPECT_FLOAT_EQ(r[1].mean_thickness, 2.25f);
  EXPECT_EQ(r[1].extreme_thickness, 2.0f);
  EXPECT_EQ(r[2].voxel_count, 8u);
  EXPECT_EQ(r[2].bbox_min, glm::i64vec3(0, 1, 1));
  EXPECT_EQ(r[3].voxel_count, 5u);
  EXPECT_EQ(r[3].mean_thickness, 2.0f);
  // Thick regions: the thickest first.
  DenseVolume<float> k(unit_grid(20, 4, 3), 0.0f);
  for (std::int64_t i = 0; i < 6; ++i) k.at(i, 1, 1) = 10;
  for (std::int64_t i = 10; i < 12; ++i) k.at(i, 1, 1) = 12;
  const auto thick = find_thickness_regions(k, ThicknessRegionKind::thick, 5.0f, 1);
  ASSERT_EQ(thick.size(), 2u);
  EXPECT_EQ(thick[0].extreme_thickness, 12.0f);
  EXPECT_EQ(thick[1].voxel_count, 6u);
  // Diagonal contact joins (26-connectivity).
  DenseVolume<float> d(unit_grid(4, 4, 4), 0.0f);
  d.at(0, 0, 0) = 2;
  d.at(1, 1, 1) = 2;
  d.at(2, 2, 2) = 2;
  const auto diag = find_thickness_regions(d, ThicknessRegionKind::thin, 3.0f, 1);
  ASSERT_EQ(diag.size(), 1u);
  EXPECT_EQ(diag[0].voxel_count, 3u);
}

// The regions by flood fill from each voxel in scan order, 26 neighbours at
// a time: the independent reference for the labelling by runs.
struct ReferenceRegion {
  ThicknessRegion region;
  std::vector<std::size_t> voxels;
};
std::vector<ReferenceRegion> flood_regions(const DenseVolume<float>& t, ThicknessRegionKind kind, float threshold) {
  const glm::i64vec3 d = t.grid().dims;
  auto selected = [&](std::size_t idx) {
    const float v = t.values()[idx];
    return v > 0 && (kind == ThicknessRegionKind::thin ? v < threshold : v > threshold);
  };
  std::vector<bool> seen(t.values().size(), false);
  std::vector<ReferenceRegion> out;
  for (std::size_t seed = 0; seed < seen.size(); ++seed) {
    if (seen[seed] || !selected(seed)) continue;
    ReferenceRegion r;
    r.region.bbox_min = d;
    r.region.bbox_max = glm::i64vec3(-1);
    r.region.extreme_thickness = t.values()[seed];
    long double sum = 0;
    std::vector<std::size_t> stack{seed};
    seen[seed] = true;
    while (!stack.empty()) {
      const std::size_t idx = stack.back();
      stack.pop_back();
      r.voxels.push_back(idx);
      const glm::i64vec3 p(static_cast<std::int64_t>(idx) % d.x, static_cast<std::int64_t>(idx) / d.x % d.y,
                           static_cast<std::int64_t>(idx) / (d.x * d.y));
      const float v = t.values()[idx];
      ++r.region.voxel_count;
      sum += v;
      r.region.centroid += glm::dvec3(p);
      r.region.bbox_min = glm::min(r.region.bbox_min, p);
      r.region.bbox_max = glm::max(r.region.bbox_max, p);
      r.region.extreme_thickness = kind == ThicknessRegionKind::thin ? std::min(r.region.extreme_thickness, v)
                                                                     : std::max(r.region.extreme_thickness, v);
      for (std::int64_t dz = -1; dz <= 1; ++dz)
        for (std::int64_t dy = -1; dy <= 1; ++dy)
          for (std::int64_t dx = -1; dx <= 1; ++dx) {
            const glm::i64vec3 q = p + glm::i64vec3(dx, dy, dz);
            if (q.x < 0 || q.y < 0 || q.z < 0 || q.x >= d.x || q.y >= d.y || q.z >= d.z) continue;
            const std::size_t n = t.index(q.x, q.y, q.z);
            if (!seen[n] && selected(n)) seen[n] = true, stack.push_back(n);
          }
    }
    r.region.centroid /= static_cast<double>(r.region.voxel_count);
    r.region.mean_thickness = static_cast<float>(sum / r.region.voxel_count);
    out.push_back(std::move(r));
  }
  return out;
}

// A map of random walls: 0 (empty) or a thickness, a blob at a time, so
// there are regions of every size, touching along faces, edges and corners.
DenseVolume<float> random_walls(const glm::i64vec3& dims, double fill, std::uint64_t seed) {
  DenseVolume<float> t(unit_grid(dims.x, dims.y, dims.z), 0.0f);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> value(0.3f, 9.0f);
  const auto voxels = static_cast<double>(dims.x * dims.y * dims.z);
  for (int blob = 0; blob < static_cast<int>(fill * voxels / 8); ++blob) {
    const glm::i64vec3 c(rng() % dims.x, rng() % dims.y, rng() % dims.z);
    const float v = value(rng);
    for (int n = 0; n < 8; ++n) {
      const glm::i64vec3 p = glm::clamp(c + glm::i64vec3(rng() % 3, rng() % 3, rng() % 3) - glm::i64vec3(1), glm::i64vec3(0),
                                        dims - glm::i64vec3(1));
      t.at(p.x, p.y, p.z) = n % 3 ? v : value(rng);
    }
  }
  return t;
}

TEST(ThicknessRegions, RunsFindTheFloodFillsRegionsForAnyThreadCount) {
  for (const double fill : {0.04, 0.3}) {
    const DenseVolume<float> t = random_walls({53, 31, 29}, fill, 7 + static_cast<std::uint64_t>(fill * 100));
    std::mt19937_64 rng(3);
    std::vector<std::size_t> probes;
    for (int p = 0; p < 4000; ++p) probes.push_back(rng() % (t.values().size() + 50));  // some past the end
    for (const auto& [kind, threshold] : {std::pair{ThicknessRegionKind::thin, 3.0f}, {ThicknessRegionKind::thick, 5.5f}}) {
      std::vector<ReferenceRegion> want = flood_regions(t, kind, threshold);
      const std::uint64_t min_voxels = 3;
      std::erase_if(want, [&](const ReferenceRegion& r) { return r.region.voxel_count < min_voxels; });
      std::stable_sort(want.begin(), want.end(), [&](const ReferenceRegion& a, const ReferenceRegion& b) {
        if (a.region.extreme_thickness != b.region.extreme_thickness)
          return kind == ThicknessRegionKind::thin ? a.region.extreme_thickness < b.region.extreme_thickness
                                                   : a.region.extreme_thickness > b.region.extreme_thickness;
        return a.region.voxel_count > b.region.voxel_count;  // then scan order: the flood's order, kept by the stable sort
      });
      ASSERT_GT(want.size(), 5u) << fill;
      std::vector<std::uint32_t> rank_of_voxel(t.values().size(), 0), want_probe(probes.size(), 0);
      for (std::size_t r = 0; r < want.size(); ++r)
        for (const std::size_t v : want[r].voxels) {
        rank_of_voxel[v] = static_cast<std::uint32_t>(r + 1);
      }
      for (std::size_t p = 0; p < probes.size(); ++p) {
        if (probes[p] < rank_of_voxel.size()) want_probe[p] = rank_of_voxel[probes[p]];
      }
      std::vector<ThicknessRegion> first;
      // 16: layers cut into runs of two or three, joined apart.
      for (const int threads : {1, 2, 3, 8, 16}) {
        std::vector<std::uint32_t> probe_regions;
        const auto got = find_thickness_regions(t, kind, threshold, min_voxels, &probes, &probe_regions, threads);
        ASSERT_EQ(got.size(), want.size()) << fill << " " << threads;
        for (std::size_t r = 0; r < got.size(); ++r) {
          const ThicknessRegion &g = got[r], &w = want[r].region;
          ASSERT_EQ(g.voxel_count, w.voxel_count) << r;
          EXPECT_EQ(g.bbox_min, w.bbox_min) << r;
          EXPECT_EQ(g.bbox_max, w.bbox_max) << r;
          EXPECT_EQ(g.centroid, w.centroid) << r;
          EXPECT_EQ(g.extreme_thickness, w.extreme_thickness) << r;
          EXPECT_FLOAT_EQ(g.mean_thickness, w.mean_thickness) << r;
          if (!first.empty()) {
            EXPECT_EQ(g.mean_thickness, first[r].mean_thickness) << "threads " << threads;
          }
        }
        EXPECT_EQ(probe_regions, want_probe) << threads;
        if (first.empty()) first = got;
      }
    }
  }
}

// The report's four queries from one pass: each query's regions are the
// flood fill's, and bit for bit what a query alone finds.
TEST(ThicknessRegions, OnePassOfManyQueriesFindsEachQuerysFloodRegions) {
  DenseVolume<float> t = random_walls({41, 27, 23}, 0.3, 11);
  // Values no query selects, amid the walls: NaN and a negative.
  t.at(5, 5, 5) = std::numeric_limits<float>::quiet_NaN();
  t.at(6, 5, 5) = -2.0f;
  const std::vector<ThicknessRegionQuery> queries{{ThicknessRegionKind::thin, 3.0f},
                                                  {ThicknessRegionKind::thin, 4.5f},
                                                  {ThicknessRegionKind::thick, 5.5f},
                                                  {ThicknessRegionKind::thick, 2.0f},
                                                  {ThicknessRegionKind::thin, 0.1f}};
  const std::uint64_t min_voxels = 2;
  for (const int threads : {1, 3, 16}) {
    const auto got = find_thickness_regions(t, queries, min_voxels, threads);
    ASSERT_EQ(got.size(), queries.size());
    for (std::size_t q = 0; q < queries.size(); ++q) {
      const ThicknessRegionKind kind = queries[q].kind;
      std::vector<ReferenceRegion> want = flood_regions(t, kind, queries[q].threshold_voxels);
      std::erase_if(want, [&](const ReferenceRegion& r) { return r.region.voxel_count < min_voxels; });
      std::stable_sort(want.begin(), want.end(), [&](const ReferenceRegion& a, const ReferenceRegion& b) {
        if (a.region.extreme_thickness != b.region.extreme_thickness)
          return kind == ThicknessRegionKind::thin ? a.region.extreme_thickness < b.region.extreme_thickness
                                                   : a.region.extreme_thickness > b.region.extreme_thickness;
        return a.region.voxel_count > b.region.voxel_count;
      });
      if (q < 4) {
        ASSERT_GT(want.size(), 3u) << q;
      }
      const auto alone = find_thickness_regions(t, kind, queries[q].threshold_voxels, min_voxels, nullptr, nullptr, threads);
      ASSERT_EQ(got[q].size(), want.size()) << "query " << q << ", threads " << threads;
      ASSERT_EQ(alone.size(), want.size()) << q;
      for (std::size_t r = 0; r < want.size(); ++r) {
        const ThicknessRegion &g = got[q][r], &w = want[r].region;
        ASSERT_EQ(g.voxel_count, w.voxel_count) << q << " " << r;
        EXPECT_EQ(g.bbox_min, w.bbox_min) << q << " " << r;
        EXPECT_EQ(g.bbox_max, w.bbox_max) << q << " " << r;
        EXPECT_EQ(g.centroid, w.centroid) << q << " " << r;
        EXPECT_EQ(g.extreme_thickness, w.extreme_thickness) << q << " " << r;
        EXPECT_FLOAT_EQ(g.mean_thickness, w.mean_thickness) << q << " " << r;
        EXPECT_EQ(g.mean_thickness, alone[r].mean_thickness) << q << " " << r;
      }
    }
  }
  EXPECT_TRUE(find_thickness_regions(t, std::vector<ThicknessRegionQuery>{}, 1).empty());
}

TEST(ThicknessRegions, HugeAndInfiniteValuesCountAtTheCap) {
  // 2^30 voxels and more (and infinity) add 2^30 to a region's mean; the
  // extreme is the value itself.
  DenseVolume<float> t(unit_grid(4, 1, 1), 0.0f);
  t.at(0, 0, 0) = std::numeric_limits<float>::infinity();
  t.at(1, 0, 0) = 1e30f;
  t.at(2, 0, 0) = 0x1p30f;
  t.at(3, 0, 0) = 0x1p29f;
  const auto thick = find_thickness_regions(t, ThicknessRegionKind::thick, 1.0f, 1);
  ASSERT_EQ(thick.size(), 1u);
  EXPECT_EQ(thick[0].voxel_count, 4u);
  EXPECT_EQ(thick[0].extreme_thickness, std::numeric_limits<float>::infinity());
  EXPECT_EQ(thick[0].mean_thickness, (3 * 0x1p30f + 0x1p29f) / 4);
}

}  // namespace
}  // namespace voxd
