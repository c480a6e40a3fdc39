// Coverage (anti-aliased) voxelization against analytic fractions: faces at
// sub-voxel offsets, boxes, a sphere's volume, and each sampling mode.
#include <algorithm>
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "support/test_meshes.h"
#include "voxd/voxelize/coverage.h"
#include "voxd/error.h"
#include "voxd/analysis/mass_properties.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd {
namespace {

using test::unit_grid;

// Length of [lo, hi] inside the voxel [i, i + 1).
double overlap(double lo, double hi, std::int64_t i) {
  return std::max(0.0, std::min(hi, i + 1.0) - std::max(lo, static_cast<double>(i)));
}

// Fraction of the k regular ray offsets of voxel j, (j + (a + 1/2) / k),
// inside [lo, hi].
double ray_fraction(double lo, double hi, std::int64_t j, int k) {
  int n = 0;
  for (int a = 0; a < k; ++a) {
    const double p = j + (a + 0.5) / k;
    n += p > lo && p < hi;
  }
  return static_cast<double>(n) / k;
}

double total(const DenseVolume<float>& c) {
  double s = 0;
  for (float v : c.values()) s += v;
  return s;
}

// A box at sub-voxel offsets: along x (the rays) the coverage is the exact
// overlap; across, the share of the k x k rays inside. Every voxel, exactly.
TEST(Coverage, BoxAtSubVoxelOffsetsIsExactAlongTheRaysAndRaySharedAcross) {
  const glm::dvec3 lo{2.3, 3.71, 1.55}, hi{9.85, 7.2, 6.05};
  const Grid g = unit_grid(12, 10, 8);
  for (int k : {1, 2, 4, 5}) {
    SCOPED_TRACE(testing::Message() << "k = " << k);
    CoverageOptions o;
    o.rays = k;
    const DenseVolume<float> c = voxelize_coverage(test::make_box(lo, hi), g, o);
    for (std::int64_t z = 0; z < 8; ++z)
      for (std::int64_t y = 0; y < 10; ++y)
        for (std::int64_t x = 0; x < 12; ++x) {
          const double want = overlap(lo.x, hi.x, x) * ray_fraction(lo.y, hi.y, y, k) * ray_fraction(lo.z, hi.z, z, k);
          ASSERT_NEAR(c.at(x, y, z), want, 1e-6) << x << "," << y << "," << z;
        }
  }
}

// A half-space (a box far larger than the grid except for its face at x0):
// the face's voxel gets x0's fractional part, whatever the number of rays.
TEST(Coverage, HalfSpaceFaceAcrossTheRaysGivesTheExactFraction) {
  for (double x0 : {3.0, 3.25, 3.5, 3.999, 4.0001}) {
    const DenseVolume<float> c = voxelize_coverage(test::make_box({-50, -50, -50}, {x0, 50, 50}), unit_grid(8, 3, 3), {});
    for (std::int64_t x = 0; x < 8; ++x) EXPECT_NEAR(c.at(x, 1, 1), overlap(-50, x0, x), 1e-6) << "x0 " << x0 << " voxel " << x;
  }
}

// Total coverage times the voxel volume is the mesh volume: a sphere and a
// torus, exact sampling and jittered.
TEST(Coverage, TotalCoverageIsTheMeshVolume) {
  const Mesh shapes[] = {test::make_icosphere({10.2, 9.7, 10.1}, 7.3, 5), test::make_torus({12.1, 11.9, 12.2}, 7.0, 2.6, 96, 48)};
  for (const Mesh& m : shapes) {
    const double volume = mesh_mass_properties(m).volume;
    Grid g = unit_grid(24, 24, 25);
    for (CoverageSampling s : {CoverageSampling::exact, CoverageSampling::stochastic}) {
      SCOPED_TRACE(to_string(s));
      CoverageOptions o;
      o.sampling = s;
      o.rays = 4;
      const double got = total(voxelize_coverage(m, g, o));
      EXPECT_NEAR(got / volume, 1.0, 1e-3) << got << " vs " << volume;
    }
  }
}

// The paper's point sampling: m points per voxel along a ray, each in or out.
TEST(Coverage, UniformSamplingCountsPointsAlongTheRay) {
  CoverageOptions o;
  o.sampling = CoverageSampling::uniform;
  o.points = 4;
  // Face at x = 3.3: points 3.125 in, 3.375 out -> 1/4; exact would say 0.3.
  const DenseVolume<float> c = voxelize_coverage(test::make_box({-50, -50, -50}, {3.3, 50, 50}), unit_grid(6, 2, 2), o);
  EXPECT_NEAR(c.at(2, 0, 0), 1.0, 1e-6);
  EXPECT_NEAR(c.at(3, 0, 0), 0.25, 1e-6);
  EXPECT_NEAR(c.at(4, 0, 0), 0.0, 1e-6);
  o.points = 10;
  EXPECT_NEAR(voxelize_coverage(test::make_box({-50, -50, -50}, {3.3, 50, 50}), unit_grid(6, 2, 2), o).at(3, 0, 0), 0.3, 1e-6);
}

TEST(Coverage, StochasticRaysRepeatWithTheSeedAndDifferWithout) {
  const Mesh m = test::make_icosphere({6.1, 6.2, 5.9}, 4.4, 4);
  CoverageOptions o;
  o.sampling = CoverageSampling::stochastic;
  o.seed = 42;
  const Grid g = unit_grid(12, 12, 12);
  const auto a = voxelize_coverage(m, g, o), b = voxelize_coverage(m, g, o);
  EXPECT_EQ(a.values(), b.values());
  o.seed = 43;
  EXPECT_NE(voxelize_coverage(m, g, o).values(), a.values());
  o.threads = 1;
  o.seed = 42;
  EXPECT_EQ(voxelize_coverage(m, g, o).values(), a.values());  // threads change nothing
}

// Shared edges and vertices on ray positions: a tessellated box whose edges
// pass through ray offsets still gives the exact box (each ray crosses each
// face once).
TEST(Coverage, RaysThroughSharedEdgesCrossOnce) {
  // k = 2: rays at j + 0.25 and j + 0.75; box corners on those lines.
  CoverageOptions o;
  o.rays = 2;
  const DenseVolume<float> c = voxelize_coverage(test::make_box({1.25, 1.25, 1.75}, {5.5, 4.75, 3.25}), unit_grid(7, 6, 5), o);
  for (std::int64_t z = 0; z < 5; ++z)
    for (std::int64_t y = 0; y < 6; ++y)
      for (std::int64_t x = 0; x < 7; ++x) {
        // Simulation of simplicity: a ray exactly on the low face counts as
        // inside, exactly on the high face as outside (displaced by +eps).
        auto frac = [](double lo, double hi, std::int64_t j) {
          int n = 0;
          for (double p : {j + 0.25, j + 0.75}) n += p >= lo && p < hi;
          return n / 2.0;
        };
        ASSERT_NEAR(c.at(x, y, z), overlap(1.25, 5.5, x) * frac(1.25, 4.75, y) * frac(1.75, 3.25, z), 1e-6)
            << x << "," << y << "," << z;
      }
}

// Thon's use of the threshold: a plate 0.4 voxels thick between voxel centre
// planes disappears from the centre-sampled solid but not from the coverage
// thresholded at 0.3.
TEST(Coverage, ThresholdKeepsAPlateThinnerThanAVoxel) {
  const Mesh plate = test::make_box({-10, -10, 2.55}, {30, 30, 2.95});
  const Grid g = unit_grid(8, 8, 6);
  EXPECT_EQ(voxelize(plate, g, {}).count(), 0u);
  CoverageOptions o;
  o.rays = 5;  // offsets 0.1, 0.3, 0.5, 0.7, 0.9: two of five rays in the plate
  const auto c = voxelize_coverage(plate, g, o);
  EXPECT_NEAR(c.at(3, 3, 2), 0.4, 1e-6);
  EXPECT_EQ(coverage_threshold(c, 0.3f).count(), 64u);
  EXPECT_EQ(coverage_threshold(c, 0.5f).count(), 0u);
  const auto bytes = coverage_bytes(c);
  EXPECT_EQ(bytes.at(3, 3, 2), 102);  // round(0.4 * 255)
  EXPECT_EQ(bytes.at(3, 3, 1), 0);
  EXPECT_THROW(coverage_threshold(c, 0.0f), Error);
}

TEST(Coverage, BadOptionsAndCancellation) {
  const Mesh m = test::make_box({1, 1, 1}, {3, 3, 3});
  CoverageOptions o;
  o.rays = 0;
  EXPECT_THROW(voxelize_coverage(m, unit_grid(4, 4, 4), o), Error);
  o.rays = 4;
  o.points = 0;
  EXPECT_THROW(voxelize_coverage(m, unit_grid(4, 4, 4), o), Error);
  JobControl control;
  control.request_cancel();
  try {
    voxelize_coverage(m, unit_grid(4, 4, 4), {}, &control);
    FAIL() << "expected Error(cancelled)";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::cancelled);
  }
  JobControl done;
  voxelize_coverage(m, unit_grid(4, 4, 4), {}, &done);
  EXPECT_DOUBLE_EQ(done.progress(), 1.0);
}

TEST(Coverage, BytesAreLroundOfTheFloatProductAndTheTotalIgnoresThreads) {
  // Every float the rounding could split: the halfway points k + 1/2 of the
  // product and their float neighbours, plus values outside [0, 1].
  const Grid g = test::make_grid({257, 3, 7});
  DenseVolume<float> c(g, 0.0f);
  std::size_t at = 0;
  for (int k = 0; k < 255 && at + 3 < c.values().size(); ++k) {
    const float half = (static_cast<float>(k) + 0.5f) / 255.0f;
    c.values()[at++] = half;
    c.values()[at++] = std::nextafter(half, 0.0f);
    c.values()[at++] = std::nextafter(half, 1.0f);
  }
  c.values()[at++] = -0.25f;
  c.values()[at++] = 1.75f;
  std::mt19937 rng(5);
  for (; at < c.values().size(); ++at) c.values()[at] = std::uniform_real_distribution<float>(0.0f, 1.0f)(rng);
  for (int threads : {1, 2, 5}) {
    const DenseVolume<std::uint8_t> bytes = coverage_bytes(c, threads);
    for (std::size_t i = 0; i < c.values().size(); ++i)
      ASSERT_EQ(bytes.values()[i], std::lround(std::clamp(c.values()[i], 0.0f, 1.0f) * 255.0f)) << c.values()[i];
  }
  double plain = 0.0;
  for (float v : c.values()) plain += v;
  const double total = covered_voxels(c, 1);
  EXPECT_NEAR(total, plain, 1e-9 * plain);
  EXPECT_EQ(covered_voxels(c, 2), total);
  EXPECT_EQ(covered_voxels(c, 7), total);
}

}  // namespace
}  // namespace voxd
