// Thickness radiography and cross-sections: exact answers on voxelized boxes
// whose voxels are known by construction, and every pixel of random volumes
// against a brute-force walk over BitVolume::get.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "support/test_meshes.h"
#include "voxd/error.h"
#include "voxd/analysis/radiography.h"
#include "voxd/analysis/section.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd {
namespace {

using test::concat;
using test::flipped;
using test::make_box;

using test::unit_grid;

BitVolume solid(const Mesh& mesh, glm::i64vec3 dims) { return voxelize(mesh, unit_grid(dims), VoxelizeOptions{}); }

// Voxel on ray (column c, row r) at position p along `axis`.
glm::i64vec3 voxel_of(int axis, std::int64_t c, std::int64_t r, std::int64_t p) {
  if (axis == 0) return {p, c, r};
  if (axis == 1) return {c, p, r};
  return {c, r, p};
}

struct Expected {
  std::uint32_t min = 0, max = 0, total = 0;
};

// The reference: one voxel at a time.
Expected brute_force_ray(const BitVolume& v, int axis, std::int64_t c, std::int64_t r) {
  Expected e;
  std::uint32_t run = 0;
  const std::int64_t n = v.grid().dims[axis];
  for (std::int64_t p = 0; p <= n; ++p) {
    const glm::i64vec3 q = voxel_of(axis, c, r, p);
    if (p < n && v.get(q.x, q.y, q.z)) {
      ++run;
      ++e.total;
    } else if (run != 0) {
      e.min = e.min == 0 ? run : std::min(e.min, run);
      e.max = std::max(e.max, run);
      run = 0;
    }
  }
  return e;
}

void expect_matches_brute_force(const BitVolume& v, int axis, int threads) {
  const ThicknessImage img = radiography(v, axis, threads);
  const glm::i64vec3 d = v.grid().dims;
  ASSERT_EQ(img.width, axis == 0 ? d.y : d.x);
  ASSERT_EQ(img.height, axis == 2 ? d.y : d.z);
  const std::size_t n = static_cast<std::size_t>(img.width) * static_cast<std::size_t>(img.height);
  ASSERT_EQ(img.min.size(), n);
  ASSERT_EQ(img.max.size(), n);
  ASSERT_EQ(img.total.size(), n);
  int mismatches = 0;
  for (int r = 0; r < img.height; ++r) {
    for (int c = 0; c < img.width; ++c) {
      const Expected e = brute_force_ray(v, axis, c, r);
      const std::size_t p = static_cast<std::size_t>(r) * static_cast<std::size_t>(img.width) + static_cast<std::size_t>(c);
      if (img.min[p] != e.min || img.max[p] != e.max || img.total[p] != e.total) {
        if (++mismatches <= 5) {
          ADD_FAILURE() << "axis " << axis << " pixel (" << c << ", " << r << "): got min/max/total " << img.min[p] << "/"
                        << img.max[p] << "/" << img.total[p] << ", expected " << e.min << "/" << e.max << "/" << e.total;
        }
      }
    }
  }
  EXPECT_EQ(mismatches, 0);
}

// Random bits with the given fill probability, plus optional solid blocks so
// the all-full fast path and runs across 64-voxel boundaries are exercised.
BitVolume random_volume(glm::i64vec3 dims, double density, std::uint32_t seed) {
  BitVolume v(unit_grid(dims));
  std::mt19937 rng(seed);
  std::bernoulli_distribution bit(density);
  for (std::int64_t k = 0; k < dims.z; ++k)
    for (std::int64_t j = 0; j < dims.y; ++j)
      for (std::int64_t i = 0; i < dims.x; ++i)
        if (bit(rng)) v.set(i, j, k, true);
  return v;
}

void fill_block(BitVolume& v, glm::i64vec3 lo, glm::i64vec3 hi, bool value) {
  for (std::int64_t k = lo.z; k < hi.z; ++k)
    for (std::int64_t j = lo.y; j < hi.y; ++j)
      for (std::int64_t i = lo.x; i < hi.x; ++i) v.set(i, j, k, value);
}

// Expects every pixel of `img` (min, max, total) to be f(c, r).
template <class F>
void expect_pixels(const ThicknessImage& img, F&& f) {
  int mismatches = 0;
  for (int r = 0; r < img.height; ++r) {
    for (int c = 0; c < img.width; ++c) {
      const Expected e = f(c, r);
      const std::size_t p = static_cast<std::size_t>(r * img.width + c);
      if ((img.min[p] != e.min || img.max[p] != e.max || img.total[p] != e.total) && ++mismatches <= 5) {
        ADD_FAILURE() << "pixel (" << c << ", " << r << "): got " << img.min[p] << "/" << img.max[p] << "/" << img.total[p]
                      << ", expected " << e.min << "/" << e.max << "/" << e.total;
      }
    }
  }
  EXPECT_EQ(mismatches, 0);
}

bool in(std::int64_t v, std::int64_t lo, std::int64_t hi) { return v >= lo && v <= hi; }  // inclusive
Expected uniform(std::uint32_t t) { return {t, t, t}; }

TEST(Radiography, BoxHasItsSideLengthsInsideItsFootprintAndZeroOutside) {
  // Voxel centres i + 0.5 inside [2,9] x [4,11] x [3,13]: i 2..8, j 4..10, k 3..12.
  const BitVolume v = solid(make_box({2, 4, 3}, {9, 11, 13}), {16, 17, 18});
  ASSERT_EQ(v.count(), 7u * 7u * 10u);
  const ThicknessImage z = radiography(v, 2);
  EXPECT_EQ(z.width, 16);
  EXPECT_EQ(z.height, 17);
  expect_pixels(z, [](int i, int j) { return in(i, 2, 8) && in(j, 4, 10) ? uniform(10) : Expected{}; });
  const ThicknessImage x = radiography(v, 0);
  EXPECT_EQ(x.width, 17);
  EXPECT_EQ(x.height, 18);
  expect_pixels(x, [](int j, int k) { return in(j, 4, 10) && in(k, 3, 12) ? uniform(7) : Expected{}; });
  const ThicknessImage y = radiography(v, 1);
  EXPECT_EQ(y.width, 16);
  EXPECT_EQ(y.height, 18);
  expect_pixels(y, [](int i, int k) { return in(i, 2, 8) && in(k, 3, 12) ? uniform(7) : Expected{}; });
}

TEST(Radiography, HollowBoxGivesTwoRunsThroughTheCavity) {
  // Outer walls: voxels 2..17 on every axis. Cavity: i 6..11, j 8..13, k 5..8.
  const Mesh hollow = concat({make_box({2, 2, 2}, {18, 18, 18}), flipped(make_box({6, 8, 5}, {12, 14, 9}))});
  const BitVolume v = solid(hollow, {20, 20, 20});
  ASSERT_EQ(v.count(), 16u * 16u * 16u - 6u * 6u * 4u);
  // Along z through the cavity: k 2..4 (3) and 9..17 (9).
  expect_pixels(radiography(v, 2), [](int i, int j) {
    if (in(i, 6, 11) && in(j, 8, 13)) return Expected{3, 9, 12};
    return in(i, 2, 17) && in(j, 2, 17) ? uniform(16) : Expected{};
  });
  // Along x: i 2..5 (4) and 12..17 (6).
  expect_pixels(radiography(v, 0), [](int j, int k) {
    if (in(j, 8, 13) && in(k, 5, 8)) return Expected{4, 6, 10};
    return in(j, 2, 17) && in(k, 2, 17) ? uniform(16) : Expected{};
  });
  // Along y: j 2..7 (6) and 14..17 (4).
  expect_pixels(radiography(v, 1), [](int i, int k) {
    if (in(i, 6, 11) && in(k, 5, 8)) return Expected{4, 6, 10};
    return in(i, 2, 17) && in(k, 2, 17) ? uniform(16) : Expected{};
  });
}

// A tube along z (annulus 9 < r <= 15 around the grid's centre line, 20
// layers): every ray along z through the wall crosses all 20 layers, rays
// through the bore nothing; a ray along x crosses the wall twice (or once
// where it only grazes the bore), each crossing as long as the annulus is
// wide on that row, counted from the definition.
TEST(Radiography, TubeGivesItsLengthAlongTheAxisAndTwoWallsAcross) {
  const int n = 34;
  BitVolume v(unit_grid({n, n, 24}));
  auto wall = [&](int i, int j) {
    const double dx = i + 0.5 - n / 2.0, dy = j + 0.5 - n / 2.0, r2 = dx * dx + dy * dy;
    return r2 > 81.0 && r2 <= 225.0;
  };
  for (int k = 2; k < 22; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        if (wall(i, j)) v.set(i, j, k, true);
  expect_pixels(radiography(v, 2), [&](int i, int j) { return wall(i, j) ? uniform(20) : Expected{}; });
  expect_pixels(radiography(v, 0), [&](int j, int k) {
    if (k < 2 || k >= 22) return Expected{};
    std::vector<std::uint32_t> runs;
    std::uint32_t run = 0;
    for (int i = 0; i <= n; ++i) {
      if (i < n && wall(i, j)) {
        ++run;
      } else if (run > 0) {
        runs.push_back(run);
        run = 0;
      }
    }
    if (runs.empty()) return Expected{};
    Expected e{runs[0], runs[0], 0};
    for (std::uint32_t r : runs) {
      e.min = std::min(e.min, r);
      e.max = std::max(e.max, r);
      e.total += r;
    }
    return e;
  });
  // The centre row crosses two walls of 6 voxels.
  const ThicknessImage x = radiography(v, 0);
  EXPECT_EQ(x.min[static_cast<std::size_t>(10 * n + n / 2)], 6u);
  EXPECT_EQ(x.total[static_cast<std::size_t>(10 * n + n / 2)], 12u);
}

// Three steps along x, heights 2, 5 and 9 voxels in z, depth j 3..8.
BitVolume stepped_block() {
  const Mesh steps = concat({make_box({2, 3, 2}, {6, 9, 4}), make_box({6, 3, 2}, {10, 9, 7}), make_box({10, 3, 2}, {14, 9, 11})});
  return solid(steps, {16, 12, 13});
}

TEST(Radiography, SteppedBlockHasOneThicknessPerStep) {
  const BitVolume v = stepped_block();
  ASSERT_EQ(v.count(), 6u * 4u * (2u + 5u + 9u));
  expect_pixels(radiography(v, 2), [](int i, int j) {
    if (!in(j, 3, 8)) return Expected{};
    return in(i, 2, 5) ? uniform(2) : in(i, 6, 9) ? uniform(5) : in(i, 10, 13) ? uniform(9) : Expected{};
  });
  expect_pixels(radiography(v, 0), [](int j, int k) {
    if (!in(j, 3, 8)) return Expected{};
    return in(k, 2, 3) ? uniform(12) : in(k, 4, 6) ? uniform(8) : in(k, 7, 10) ? uniform(4) : Expected{};
  });
  expect_pixels(radiography(v, 1), [](int i, int k) {
    const int top = in(i, 2, 5) ? 3 : in(i, 6, 9) ? 6 : in(i, 10, 13) ? 10 : -1;
    return in(k, 2, top) ? uniform(6) : Expected{};
  });
}

TEST(Radiography, RandomVolumesMatchBruteForceOnEveryAxis) {
  struct Case {
    glm::i64vec3 dims;
    double density;
  };
  const Case cases[] = {
      {{67, 45, 33}, 0.5}, {{67, 45, 33}, 0.9}, {{64, 64, 64}, 0.1}, {{1, 1, 1}, 1.0}, {{3, 130, 2}, 0.7}, {{130, 7, 70}, 0.97},
  };
  std::uint32_t seed = 1;
  for (const Case& c : cases) {
    const BitVolume v = random_volume(c.dims, c.density, seed++);
    for (int axis = 0; axis < 3; ++axis) {
      SCOPED_TRACE(::testing::Message() << "dims " << c.dims.x << "x" << c.dims.y << "x" << c.dims.z << " density "
                                        << c.density << " axis " << axis);
      expect_matches_brute_force(v, axis, 0);
    }
  }
}

TEST(Radiography, SolidBlocksAcrossWordsMatchBruteForce) {
  // Solid regions several 64-voxel blocks long (the all-full fast path and
  // runs crossing word and block boundaries), ended by empty blocks (the
  // all-empty path must close open runs), with noise and a few holes.
  BitVolume v = random_volume({200, 150, 140}, 0.02, 99);
  fill_block(v, {0, 0, 0}, {192, 140, 130}, true);
  fill_block(v, {10, 64, 64}, {12, 66, 66}, false);   // a hole inside full blocks
  fill_block(v, {70, 0, 0}, {71, 150, 140}, false);   // a cut plane at x = 70
  fill_block(v, {0, 127, 0}, {200, 129, 140}, false);  // runs along y end at a block edge
  fill_block(v, {0, 0, 63}, {200, 150, 64}, false);   // runs along z end just before a block
  for (int threads : {1, 3}) {
    for (int axis = 0; axis < 3; ++axis) {
      SCOPED_TRACE(::testing::Message() << "axis " << axis << " threads " << threads);
      expect_matches_brute_force(v, axis, threads);
    }
  }
}

TEST(Radiography, EmptyVolumeAndBadAxis) {
  const BitVolume v(unit_grid({5, 6, 7}));
  const ThicknessImage img = radiography(v, 1);
  EXPECT_EQ(img.width, 5);
  EXPECT_EQ(img.height, 7);
  EXPECT_EQ(img.total, UnclearedVector<std::uint32_t>(35, 0));
  EXPECT_EQ(img.min, UnclearedVector<std::uint32_t>(35, 0));
  for (int axis : {-1, 3}) {
    try {
      radiography(v, axis);
      ADD_FAILURE() << "axis " << axis << " accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::invalid_argument);
      EXPECT_NE(std::string(e.what()).find("axis"), std::string::npos) << e.what();
    }
  }
}

TEST(ThicknessStats, SteppedBlockByHand) {
  // z totals: 24 rays of 2, 24 of 5, 24 of 9.
  const ThicknessStats s = thickness_stats(radiography(stepped_block(), 2).total, 8);
  EXPECT_EQ(s.rays, 72u);
  EXPECT_EQ(s.min, 2u);
  EXPECT_EQ(s.max, 9u);
  EXPECT_DOUBLE_EQ(s.mean, 16.0 / 3.0);
  EXPECT_EQ(s.p5, 2u);    // rank ceil(3.6) = 4
  EXPECT_EQ(s.p50, 5u);   // rank 36
  EXPECT_EQ(s.p95, 9u);   // rank ceil(68.4) = 69
  EXPECT_DOUBLE_EQ(s.bin_width, 1.0);  // values 2..9 over 8 bins
  EXPECT_EQ(s.histogram, (std::vector<std::uint64_t>{24, 0, 0, 24, 0, 0, 0, 24}));
}

TEST(ThicknessStats, MatchesSortedReferenceOnRandomMaps) {
  const BitVolume v = random_volume({67, 45, 33}, 0.6, 7);
  for (int axis = 0; axis < 3; ++axis) {
    const ThicknessImage img = radiography(v, axis);
    for (const auto* map : {&img.min, &img.max, &img.total}) {
      for (int bins : {1, 5, 32}) {
        const ThicknessStats s = thickness_stats(*map, bins);
        std::vector<std::uint32_t> hits;
        for (std::uint32_t x : *map) if (x != 0) hits.push_back(x);
        std::sort(hits.begin(), hits.end());
        ASSERT_FALSE(hits.empty());
        const std::size_t n = hits.size();
        EXPECT_EQ(s.rays, n);
        EXPECT_EQ(s.min, hits.front());
        EXPECT_EQ(s.max, hits.back());
        double sum = 0;
        for (std::uint32_t x : hits) sum += x;
        EXPECT_NEAR(s.mean, sum / static_cast<double>(n), 1e-9);
        auto rank = [&](double p) { return hits[static_cast<std::size_t>(std::max(1.0, std::ceil(p / 100.0 * static_cast<double>(n)))) - 1]; };
        EXPECT_EQ(s.p5, rank(5));
        EXPECT_EQ(s.p50, rank(50));
        EXPECT_EQ(s.p95, rank(95));
        std::vector<std::uint64_t> hist(static_cast<std::size_t>(bins), 0);
        const double width = static_cast<double>(hits.back() - hits.front() + 1) / bins;
        for (std::uint32_t x : hits) ++hist[static_cast<std::size_t>(std::floor((x - hits.front()) / width + 1e-12))];
        EXPECT_EQ(s.histogram, hist);
        EXPECT_DOUBLE_EQ(s.bin_width, width);
      }
    }
  }
}

TEST(ThicknessStats, NoMaterialAndBadBins) {
  const std::vector<std::uint32_t> zeros(10, 0);
  const ThicknessStats s = thickness_stats(zeros);
  EXPECT_EQ(s.rays, 0u);
  EXPECT_EQ(s.max, 0u);
  EXPECT_TRUE(s.histogram.empty());
  EXPECT_THROW(thickness_stats(zeros, 0), Error);
}

TEST(CrossSection, SteppedBlockPlanes) {
  const BitVolume v = stepped_block();
  const GreyImage8 z = cross_section(v, 2, 5);  // cut through steps 2 and 3 (heights 5, 9)
  ASSERT_EQ(z.width, 16);
  ASSERT_EQ(z.height, 12);
  for (int j = 0; j < 12; ++j)
    for (int i = 0; i < 16; ++i)
      EXPECT_EQ(z.pixels[static_cast<std::size_t>(j * 16 + i)], in(i, 6, 13) && in(j, 3, 8) ? 255 : 0) << i << "," << j;
  const GreyImage8 x = cross_section(v, 0, 7);  // the middle step: k 2..6
  ASSERT_EQ(x.width, 12);
  ASSERT_EQ(x.height, 13);
  for (int k = 0; k < 13; ++k)
    for (int j = 0; j < 12; ++j)
      EXPECT_EQ(x.pixels[static_cast<std::size_t>(k * 12 + j)], in(j, 3, 8) && in(k, 2, 6) ? 255 : 0) << j << "," << k;
  const GreyImage8 y = cross_section(v, 1, 4);  // the staircase profile
  ASSERT_EQ(y.width, 16);
  ASSERT_EQ(y.height, 13);
  for (int k = 0; k < 13; ++k)
    for (int i = 0; i < 16; ++i) {
      const int top = in(i, 2, 5) ? 3 : in(i, 6, 9) ? 6 : in(i, 10, 13) ? 10 : -1;
      EXPECT_EQ(y.pixels[static_cast<std::size_t>(k * 16 + i)], in(k, 2, top) ? 255 : 0) << i << "," << k;
    }
}

TEST(CrossSection, RandomVolumeEveryPlaneMatchesGet) {
  const BitVolume v = random_volume({67, 45, 33}, 0.5, 3);
  const glm::i64vec3 d = v.grid().dims;
  for (int axis = 0; axis < 3; ++axis) {
    for (std::int64_t index = 0; index < d[axis]; ++index) {
      const GreyImage8 s = cross_section(v, axis, index);
      int mismatches = 0;
      for (int r = 0; r < s.height; ++r)
        for (int c = 0; c < s.width; ++c) {
          const glm::i64vec3 q = voxel_of(axis, c, r, index);
          if (s.pixels[static_cast<std::size_t>(r * s.width + c)] != (v.get(q.x, q.y, q.z) ? 255 : 0)) ++mismatches;
        }
      EXPECT_EQ(mismatches, 0) << "axis " << axis << " index " << index;
    }
  }
}

TEST(CrossSection, IndexOutsideTheGridIsRejected) {
  const BitVolume v = stepped_block();
  for (std::int64_t index : {std::int64_t{-1}, std::int64_t{16}}) {
    try {
      cross_section(v, 0, index);
      ADD_FAILURE() << "index " << index << " accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::invalid_argument);
      EXPECT_NE(std::string(e.what()).find("outside 0..15"), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(cross_section(v, 3, 0), Error);
}

TEST(CrossSection, IndexFromModelCoordinate) {
  Grid g;
  g.origin = {-1.0, 0.5, 2.0};
  g.voxel_size = 0.25;
  g.dims = {8, 4, 16};
  EXPECT_EQ(section_index(g, 0, -1.0), 0);
  EXPECT_EQ(section_index(g, 0, -0.76), 0);
  EXPECT_EQ(section_index(g, 0, -0.75), 1);
  EXPECT_EQ(section_index(g, 0, 0.99), 7);
  EXPECT_EQ(section_index(g, 1, 1.4), 3);
  EXPECT_EQ(section_index(g, 2, 3.1), 4);
  for (double bad : {1.0, -1.01, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    try {
      section_index(g, 0, bad);
      ADD_FAILURE() << bad << " accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::invalid_argument);
      EXPECT_NE(std::string(e.what()).find("outside the grid"), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(section_index(g, 2, 5.999), 15);
  EXPECT_THROW(section_index(g, 2, 6.0), Error);
}

}  // namespace
}  // namespace voxd
