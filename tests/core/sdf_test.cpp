// Signed distance field against its definition: the point-triangle distance
// against an independent brute force, every band voxel against the minimum
// over all triangles, analytic distances for a box and a sphere, the sign
// against the solid voxelization, plus conventions, units, threads and
// cancellation.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <thread>

#include <glm/geometric.hpp>

#include "support/test_meshes.h"
#include "voxd/error.h"
#include "voxd/detail/sdf_tuning.h"
#include "voxd/voxelize/sdf.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd {
namespace {

using glm::dvec3;
using LVec = std::array<long double, 3>;

Grid make_grid(dvec3 origin, double voxel_size, std::int64_t nx, std::int64_t ny, std::int64_t nz) {
  Grid g;
  g.origin = origin;
  g.voxel_size = voxel_size;
  g.dims = {nx, ny, nz};
  return g;
}

// ---------------------------------------------------------------------------
// Reference point-triangle distance, in long double and by other means than
// the engine's region tests: the minimum over a barycentric sampling of the
// triangle, the closest points of the three edges (projection, clamped), and
// the projection of p on the plane when its barycentric coordinates are all
// non-negative. Every candidate is a point of the triangle, so the result is
// never below the true distance, and one candidate is the true closest point.
//
// The normal is exact: edge vectors of float vertices hold at most ~30
// significant bits, so their products fit long double's 64, and only the
// final differences round. Barycentric coordinates come from cross products
// with it, (ab x ap) . n / |n|^2, which stay accurate on slivers where the
// normal equations' determinant |ab|^2 |ac|^2 - (ab . ac)^2 cancels.

LVec lv(const dvec3& v) { return {v.x, v.y, v.z}; }
LVec sub(const LVec& a, const LVec& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
long double ldot(const LVec& a, const LVec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
LVec lcross(const LVec& a, const LVec& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
LVec axpy(const LVec& a, long double s, const LVec& x) { return {a[0] + s * x[0], a[1] + s * x[1], a[2] + s * x[2]}; }

long double reference_distance2(const dvec3& p_, const dvec3& a_, const dvec3& b_, const dvec3& c_) {
  const LVec p = lv(p_), a = lv(a_), b = lv(b_), c = lv(c_);
  const LVec ab = sub(b, a), ac = sub(c, a);
  long double best = std::numeric_limits<long double>::infinity();
  auto consider = [&](const LVec& q) {
    const LVec d = sub(p, q);
    best = std::min(best, ldot(d, d));
  };
  constexpr int kSamples = 48;
  for (int i = 0; i <= kSamples; ++i)
    for (int j = 0; i + j <= kSamples; ++j)
      consider(axpy(axpy(a, static_cast<long double>(i) / kSamples, ab), static_cast<long double>(j) / kSamples, ac));
  const LVec edges[3][2] = {{a, b}, {b, c}, {c, a}};
  for (const auto& e : edges) {
    const LVec d = sub(e[1], e[0]);
    const long double dd = ldot(d, d);
    const long double t = dd > 0 ? std::clamp(ldot(sub(p, e[0]), d) / dd, 0.0L, 1.0L) : 0.0L;
    consider(axpy(e[0], t, d));
  }
  const LVec n = lcross(ab, ac), ap = sub(p, a);
  const long double nn = ldot(n, n);
  if (nn > 0) {
    const long double u = ldot(lcross(ap, ac), n) / nn, v = ldot(lcross(ab, ap), n) / nn;
    if (u >= 0 && v >= 0 && u + v <= 1) consider(axpy(axpy(a, u, ab), v, ac));
  }
  return best;
}

// Float-exact vertices, as the engine gets them from a Mesh.
dvec3 as_float(const dvec3& v) { return dvec3(glm::vec3(v)); }

void expect_distance_matches(const dvec3& p, const dvec3& a, const dvec3& b, const dvec3& c, const char* kind) {
  const double got = std::sqrt(point_triangle_distance2(p, a, b, c));
  const double want = static_cast<double>(std::sqrt(reference_distance2(p, a, b, c)));
  const double scale = std::max({glm::length(b - a), glm::length(c - a), glm::length(c - b)});
  EXPECT_NEAR(got, want, 1e-9 * want + 1e-13 * scale) << kind << ": p (" << p.x << "," << p.y << "," << p.z << ")";
}

TEST(PointTriangleDistance, MatchesBruteForceOnRandomAndDegenerateTriangles) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  auto random_vec = [&] { return dvec3(unit(rng), unit(rng), unit(rng)); };
  int checked = 0;
  for (int n = 0; n < 360; ++n) {
    const dvec3 offset = random_vec() * 10.0;
    const double size = std::pow(10.0, unit(rng) * 2.0);
    dvec3 a = offset + size * random_vec(), b = offset + size * random_vec(), c = offset + size * random_vec();
    const char* kind = "random";
    const int shape = n % 6;  // 0 and 5: random; 1 to 4: thin or degenerate
    const double thin = std::pow(10.0, -2.0 - (n / 6) % 11);  // 1e-2 .. 1e-12
    if (shape == 1) {  // cap: c just off the segment ab
      kind = "cap sliver";
      c = a + 0.37 * (b - a) + thin * size * glm::normalize(random_vec());
    } else if (shape == 2) {  // needle: b just off a
      kind = "needle sliver";
      b = a + thin * size * glm::normalize(random_vec());
    } else if (shape == 3) {  // exactly collinear (integer coordinates)
      kind = "collinear";
      const dvec3 base = glm::floor(offset), step = glm::floor(random_vec() * 8.0);
      a = base;
      b = base + 2.0 * step;
      c = base + (n % 12 < 6 ? 1.0 : 3.0) * step;
    } else if (shape == 4) {  // two or three coincident vertices
      kind = "coincident";
      b = a;
      if (n % 12 == 4) c = a;
    }
    a = as_float(a);
    b = as_float(b);
    c = as_float(c);
    // The exact normal and the smallest height, to aim points at the face.
    const LVec ln = lcross(sub(lv(b), lv(a)), sub(lv(c), lv(a)));
    const long double area2 = std::sqrt(ldot(ln, ln));
    const double longest = std::max({glm::length(b - a), glm::length(c - a), glm::length(c - b)});
    for (int q = 0; q < 16; ++q) {
      dvec3 p = offset + 2.0 * size * random_vec();
      if (q >= 8 && area2 > 0) {
        // Just above or below the face, where the plane decides, or just off
        // an edge (the jitter spans twice the smallest height).
        const double u = 0.5 * (unit(rng) + 1.0), v = 0.5 * (unit(rng) + 1.0) * (1.0 - u);
        const dvec3 normal(ln[0] / area2, ln[1] / area2, ln[2] / area2);
        const double height = static_cast<double>(area2) / longest;
        p = a + u * (b - a) + v * (c - a) + normal * (size * std::pow(10.0, -1.0 - (q - 8) % 6)) +
            2.0 * height * random_vec();
      }
      expect_distance_matches(p, a, b, c, kind);
      ++checked;
    }
  }
  EXPECT_EQ(checked, 360 * 16);
}

TEST(PointTriangleDistance, RegionsOfOneTriangle) {
  const dvec3 a(0, 0, 0), b(4, 0, 0), c(0, 3, 0);
  EXPECT_DOUBLE_EQ(point_triangle_distance2({1, 1, 2}, a, b, c), 4.0);        // face
  EXPECT_DOUBLE_EQ(point_triangle_distance2({-1, -2, 0}, a, b, c), 5.0);      // vertex a
  EXPECT_DOUBLE_EQ(point_triangle_distance2({6, 0, 1}, a, b, c), 5.0);        // vertex b
  EXPECT_DOUBLE_EQ(point_triangle_distance2({0, 5, 0}, a, b, c), 4.0);        // vertex c
  EXPECT_DOUBLE_EQ(point_triangle_distance2({2, -3, 4}, a, b, c), 25.0);      // edge ab
  EXPECT_DOUBLE_EQ(point_triangle_distance2({-2, 1, 0}, a, b, c), 4.0);       // edge ca
  EXPECT_NEAR(point_triangle_distance2({4, 3, 0}, a, b, c), 2.4 * 2.4, 1e-12);  // edge bc
}

// ---------------------------------------------------------------------------
// Brute force over every triangle at every voxel centre.

double brute_distance(const Mesh& mesh, const dvec3& p) {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t)
    best = std::min(best, point_triangle_distance2(p, dvec3(mesh.corner(t, 0)), dvec3(mesh.corner(t, 1)),
                                                   dvec3(mesh.corner(t, 2))));
  return std::sqrt(best);
}

template <typename Check>
void for_each_voxel(const Grid& g, Check&& check) {
  for (std::int64_t k = 0; k < g.dims.z; ++k)
    for (std::int64_t j = 0; j < g.dims.y; ++j)
      for (std::int64_t i = 0; i < g.dims.x; ++i) check(i, j, k);
}

// Sign: negative exactly where the solid voxelization is filled (a value of
// 0, on the surface, has no sign).
void expect_sign_matches_solid(const DenseVolume<float>& sdf, const Mesh& mesh, InsideTest inside = InsideTest::parity) {
  const BitVolume solid = voxelize(mesh, sdf.grid(), {VoxelMode::solid, inside, 0});
  std::int64_t wrong = 0;
  for_each_voxel(sdf.grid(), [&](std::int64_t i, std::int64_t j, std::int64_t k) {
    const float v = sdf.at(i, j, k);
    if (v != 0.0f && (v < 0.0f) != solid.get(i, j, k) && ++wrong <= 5)
      ADD_FAILURE() << "sign at (" << i << "," << j << "," << k << "): " << v;
  });
  EXPECT_EQ(wrong, 0);
}

// Band values against the brute force (within `tolerance` model units), the
// rest exactly +-band.
void expect_band_matches_brute_force(const DenseVolume<float>& sdf, const Mesh& mesh, double band, double tolerance) {
  const Grid& g = sdf.grid();
  const double B = band * g.voxel_size;
  std::int64_t wrong = 0, in_band = 0;
  for_each_voxel(g, [&](std::int64_t i, std::int64_t j, std::int64_t k) {
    const double want = brute_distance(mesh, g.center(i, j, k));
    const double got = std::abs(sdf.at(i, j, k));
    const bool ok = want <= B ? std::abs(got - want) <= tolerance : got == static_cast<float>(B);
    in_band += want <= B;
    if (!ok && ++wrong <= 5)
      ADD_FAILURE() << "voxel (" << i << "," << j << "," << k << "): got " << got << ", brute force " << want;
  });
  EXPECT_EQ(wrong, 0);
  EXPECT_GT(in_band, 1000);
}

TEST(SignedDistanceField, SphereBandIsExactDistanceToTheMesh) {
  // Radius 14 voxels on 36^3, voxel 0.5: the icosphere at level 4 (5120
  // triangles) stays within ~0.02 voxel of the sphere.
  const dvec3 centre(0.13, -0.21, 0.07);
  const double R = 7.0, vs = 0.5;
  const Mesh mesh = test::make_icosphere(centre, R, 4);
  const Grid g = make_grid(centre - 9.0 + 0.031, vs, 36, 36, 36);
  SdfOptions o;
  const DenseVolume<float> sdf = signed_distance_field(mesh, g, o);
  expect_sign_matches_solid(sdf, mesh);

  // The mesh lies in the shell [r_min, r_max] around the centre, so its
  // distance function is within r_max - r_min of the sphere's.
  double r_max = 0.0;
  for (const glm::vec3& v : mesh.vertices) r_max = std::max(r_max, glm::length(dvec3(v) - centre));
  const double r_min = brute_distance(mesh, centre);
  const double polygon_error = std::max(r_max, R) - r_min;
  ASSERT_LT(polygon_error, 0.05 * vs);

  const double B = o.band * vs;
  std::int64_t wrong = 0, in_band = 0;
  for_each_voxel(g, [&](std::int64_t i, std::int64_t j, std::int64_t k) {
    const dvec3 p = g.center(i, j, k);
    const double sphere = std::abs(glm::length(p - centre) - R);
    const double got = std::abs(sdf.at(i, j, k));
    bool ok;
    if (sphere > B + polygon_error + vs) {
      ok = got == static_cast<float>(B);  // certainly beyond the band: no brute force needed
    } else {
      const double want = brute_distance(mesh, p);
      in_band += want <= B;
      ok = want <= B ? std::abs(got - want) <= 1e-4 * vs && std::abs(got - sphere) <= polygon_error + 1e-4 * vs
                     : got == static_cast<float>(B);
    }
    if (!ok && ++wrong <= 5) ADD_FAILURE() << "voxel (" << i << "," << j << "," << k << "): got " << got;
  });
  EXPECT_EQ(wrong, 0);
  EXPECT_GT(in_band, 10000);
}

// The box [lo, hi]: inside, the distance to the nearest face; outside, to
// the box. Coordinates are multiples of 1/16 (exact in float), none of them
// 0.25 modulo 0.5 like the voxel centres, so no centre lies on a face.
struct BoxCase {
  dvec3 lo{1.375, 0.8125, 2.0625}, hi{8.6875, 7.9375, 8.3125};
  Grid grid = make_grid({-0.5, -1.0, 0.0}, 0.5, 22, 21, 23);
  double signed_distance(const dvec3& p) const {
    const dvec3 out = glm::max(glm::max(lo - p, p - hi), dvec3(0.0));
    if (out != dvec3(0.0)) return glm::length(out);
    const dvec3 in = glm::min(p - lo, hi - p);
    return -std::min({in.x, in.y, in.z});
  }
};

TEST(SignedDistanceField, BoxEqualsAnalyticDistance) {
  const BoxCase box;
  const Mesh mesh = test::make_box(box.lo, box.hi);
  const double vs = box.grid.voxel_size;
  for (const bool full : {true, false}) {
    SCOPED_TRACE(full ? "full" : "band");
    SdfOptions o;
    o.full = full;
    o.band = 2.5;
    const DenseVolume<float> sdf = signed_distance_field(mesh, box.grid, o);
    std::int64_t wrong = 0, beyond = 0;
    for_each_voxel(box.grid, [&](std::int64_t i, std::int64_t j, std::int64_t k) {
      const double want = box.signed_distance(box.grid.center(i, j, k));
      const double got = sdf.at(i, j, k);
      bool ok;
      if (full || std::abs(want) <= o.band * vs) {
        ok = std::abs(got - want) <= 1e-5 * vs;
      } else {
        ++beyond;
        ok = got == std::copysign(static_cast<float>(o.band * vs), want);
      }
      if (!ok && ++wrong <= 5)
        ADD_FAILURE() << "voxel (" << i << "," << j << "," << k << "): got " << got << ", want " << want;
    });
    EXPECT_EQ(wrong, 0);
    if (!full) {
      EXPECT_GT(beyond, 1000);  // both sides of the band are exercised
    }
  }
}

TEST(SignedDistanceField, TorusBandEqualsBruteForce) {
  const Mesh mesh = test::make_torus({0.2, -0.3, 0.1}, 8.0, 3.3, 48, 24);
  const Grid g = make_grid({-13.1, -13.2, -5.3}, 0.8, 33, 33, 14);
  SdfOptions o;
  const DenseVolume<float> sdf = signed_distance_field(mesh, g, o);
  expect_band_matches_brute_force(sdf, mesh, o.band, 1e-4 * g.voxel_size);
  expect_sign_matches_solid(sdf, mesh);
}

// Triangles much smaller than the band (a fifth of a voxel's face and
// less), as on the benchmark mesh: the band goes through the clusters of
// neighbouring triangles. Sampled voxels against the brute force, bit for
// bit, in the band and beyond it.
TEST(SignedDistanceField, FineMeshBandEqualsBruteForceBitForBit) {
  const Mesh mesh = test::make_torus({0.05, -0.02, 0.03}, 4.0, 1.5, 240, 90);
  const Grid g = make_grid({-5.83, -5.91, -1.87}, 0.1, 118, 118, 38);
  SdfOptions o;
  const DenseVolume<float> sdf = signed_distance_field(mesh, g, o);
  const double B = o.band * g.voxel_size;
  std::mt19937 rng(5);
  std::uniform_int_distribution<std::int64_t> ix(0, g.dims.x - 1), iy(0, g.dims.y - 1), iz(0, g.dims.z - 1);
  std::int64_t wrong = 0, in_band = 0;
  for (int n = 0; n < 4000; ++n) {
    const std::int64_t i = ix(rng), j = iy(rng), k = iz(rng);
    const double d = brute_distance(mesh, g.center(i, j, k));
    const float got = std::abs(sdf.at(i, j, k));
    if (d > B * (1.0 - 1e-6) && d < B * (1.0 + 1e-6)) continue;  // at the band's edge either is right
    in_band += d < B;
    const float want = d < B ? static_cast<float>(d) : static_cast<float>(B);
    if (got != want && ++wrong <= 5)
      ADD_FAILURE() << "voxel (" << i << "," << j << "," << k << "): got " << got << ", brute force " << d;
  }
  EXPECT_EQ(wrong, 0);
  EXPECT_GT(in_band, 500);
}

TEST(SignedDistanceField, SignFollowsTheChosenInsideTest) {
  // Two overlapping spheres: parity (and vote: two crossings along every
  // axis) calls the overlap outside, the winding number (2) inside.
  const Mesh mesh = test::concat({test::make_icosphere({-1.5, 0, 0}, 4.0, 3), test::make_icosphere({1.5, 0, 0}, 4.0, 3)});
  const Grid g = make_grid({-7.0, -5.0, -5.0}, 0.5, 28, 20, 20);
  for (const InsideTest inside : {InsideTest::parity, InsideTest::vote, InsideTest::winding}) {
    SCOPED_TRACE(to_string(inside));
    SdfOptions o;
    o.inside = inside;
    expect_sign_matches_solid(signed_distance_field(mesh, g, o), mesh, inside);
    // The solid handed back is that voxelization, and the values the same.
    BitVolume solid;
    const DenseVolume<float> with_solid = signed_distance_field(mesh, g, o, nullptr, &solid);
    const BitVolume expected = voxelize(mesh, g, {VoxelMode::solid, inside, 0});
    ASSERT_EQ(solid.word_count(), expected.word_count());
    EXPECT_TRUE(std::equal(solid.data(), solid.data() + solid.word_count(), expected.data()));
    EXPECT_EQ(with_solid.values(), signed_distance_field(mesh, g, o).values());
  }
  SdfOptions parity, winding;
  winding.inside = InsideTest::winding;
  EXPECT_GT(signed_distance_field(mesh, g, parity).at(14, 10, 10), 0.0f);  // centre of the overlap
  EXPECT_LT(signed_distance_field(mesh, g, winding).at(14, 10, 10), 0.0f);
}

TEST(SignedDistanceField, SignConventionAndUnits) {
  const Mesh mesh = test::make_icosphere({0.1, 0.2, -0.1}, 3.1, 3);
  const Grid g = make_grid({-4.0, -4.0, -4.0}, 0.4, 20, 20, 20);
  for (const bool full : {false, true}) {
    SCOPED_TRACE(full ? "full" : "band");
    SdfOptions o;
    o.full = full;
    const DenseVolume<float> base = signed_distance_field(mesh, g, o);
    SdfOptions flipped = o;
    flipped.sign = SignConvention::inside_positive;
    const DenseVolume<float> positive = signed_distance_field(mesh, g, flipped);
    SdfOptions voxels = o;
    voxels.model_units = false;
    const DenseVolume<float> in_voxels = signed_distance_field(mesh, g, voxels);
    std::int64_t negative = 0, wrong = 0;
    for (std::size_t v = 0; v < base.values().size(); ++v) {
      const float b = base.values()[v];
      negative += b < 0.0f;
      if (positive.values()[v] != -b && ++wrong <= 5) ADD_FAILURE() << "sign at " << v;
      const float x = in_voxels.values()[v];
      const bool ok = std::abs(b) == static_cast<float>(o.band * g.voxel_size) && !full
                          ? x == std::copysign(static_cast<float>(o.band), b)
                          : std::abs(x - b / g.voxel_size) <= 2e-7 * std::abs(b / g.voxel_size);
      if (!ok && ++wrong <= 5) ADD_FAILURE() << "units at " << v << ": " << x << " vs " << b;
    }
    EXPECT_EQ(wrong, 0);
    EXPECT_GT(negative, 1000);
  }
}

// A mesh with a bit of everything, in disjoint parts: a torus, a sphere in
// its hole, a box, and a degenerate (zero-area) triangle.
Mesh mesh_of_box() { return test::make_box({0, 0, 0}, {1, 1, 1}); }

Mesh mixed_mesh() {
  Mesh m = test::concat({test::make_torus({0.3, 0.1, 0.0}, 4.0, 1.3, 40, 20), test::make_icosphere({0.2, 0.3, 0.4}, 1.7, 3),
                         test::make_box({-5.5, 5.6, -1.2}, {-2.1, 6.8, 2.3})});
  const auto base = static_cast<std::uint32_t>(m.vertices.size());
  m.vertices.push_back({6.0f, -5.0f, 1.0f});
  m.vertices.push_back({7.0f, -4.0f, 2.0f});
  m.vertices.push_back({8.0f, -3.0f, 3.0f});
  m.triangles.push_back({base, base + 1, base + 2});
  return m;
}

TEST(SignedDistanceField, FullEqualsBruteForceEverywhere) {
  // Same point-triangle function, minimum in double, one rounding: so the
  // values must be equal, not just close.
  const Mesh mesh = mixed_mesh();
  const Grid g = make_grid({-7.3, -7.1, -4.2}, 0.55, 28, 27, 16);
  const BitVolume solid = voxelize(mesh, g, {});
  for (const bool model_units : {true, false}) {
    SCOPED_TRACE(model_units ? "model units" : "voxels");
    SdfOptions o;
    o.full = true;
    o.band = 1.5;
    o.model_units = model_units;
    const DenseVolume<float> sdf = signed_distance_field(mesh, g, o);
    std::int64_t wrong = 0;
    for_each_voxel(g, [&](std::int64_t i, std::int64_t j, std::int64_t k) {
      const double d = brute_distance(mesh, g.center(i, j, k));
      auto want = static_cast<float>(model_units ? d : d * (1.0 / g.voxel_size));
      if (want != 0.0f && solid.get(i, j, k)) want = -want;
      if (sdf.at(i, j, k) != want && ++wrong <= 5)
        ADD_FAILURE() << "voxel (" << i << "," << j << "," << k << "): got " << sdf.at(i, j, k) << ", want " << want;
    });
    EXPECT_EQ(wrong, 0);
  }
}

// The nearest-triangle queries beyond the band by Embree's rtcPointQuery:
// the same bits as the oriented-box tree, and as the brute force.
TEST(SignedDistanceField, EmbreeQueriesEqualTheTreeAndBruteForce) {
  const Mesh mesh = mixed_mesh();
  const Grid g = make_grid({-7.3, -7.1, -4.2}, 0.55, 28, 27, 16);
  SdfOptions o;
  o.full = true;
  o.band = 1.5;
  detail::SdfTuning embree;
  embree.nearest = detail::SdfTuning::Nearest::embree;
  const DenseVolume<float> a = signed_distance_field(mesh, g, o), b = signed_distance_field(mesh, g, o, nullptr, embree);
  ASSERT_EQ(a.values().size(), b.values().size());
  EXPECT_EQ(std::memcmp(a.values().data(), b.values().data(), a.values().size() * sizeof(float)), 0);
  std::int64_t wrong = 0;
  for_each_voxel(g, [&](std::int64_t i, std::int64_t j, std::int64_t k) {
    const auto want = static_cast<float>(brute_distance(mesh, g.center(i, j, k)));
    if (std::abs(b.at(i, j, k)) != want && ++wrong <= 5)
      ADD_FAILURE() << "voxel (" << i << "," << j << "," << k << "): got " << b.at(i, j, k) << ", want " << want;
  });
  EXPECT_EQ(wrong, 0);
}

TEST(SignedDistanceField, ThreadCountDoesNotChangeABit) {
  const Mesh mesh = mixed_mesh();
  const Grid g = make_grid({-7.3, -7.1, -4.2}, 0.3, 50, 48, 30);
  for (const bool full : {false, true}) {
    SCOPED_TRACE(full ? "full" : "band");
    SdfOptions one, many;
    one.full = many.full = full;
    one.threads = 1;
    many.threads = 5;
    const DenseVolume<float> a = signed_distance_field(mesh, g, one), b = signed_distance_field(mesh, g, many);
    ASSERT_EQ(a.values().size(), b.values().size());
    EXPECT_EQ(std::memcmp(a.values().data(), b.values().data(), a.values().size() * sizeof(float)), 0);
  }
}

TEST(SignedDistanceField, ProgressReachesOneAndCancelThrows) {
  const Mesh mesh = test::make_torus({0, 0, 0}, 4.0, 1.5, 200, 100);
  const Grid g = make_grid({-6.0, -6.0, -2.0}, 0.1, 120, 120, 40);
  SdfOptions o;
  o.full = true;
  {
    JobControl control;
    signed_distance_field(mesh, g, o, &control);
    EXPECT_EQ(control.progress(), 1.0);
  }
  {
    JobControl control;
    control.request_cancel();
    try {
      signed_distance_field(mesh, g, o, &control);
      ADD_FAILURE() << "no exception";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::cancelled);
    }
  }
  // Cancelled while running: during the band (progress 0.15 to 0.25 with
  // `full`), and during the queries beyond it.
  for (const double at : {0.2, 0.7}) {
    SCOPED_TRACE(at);
    JobControl control;
    std::atomic<bool> stop{false};
    std::thread canceller([&] {
      while (!stop && control.progress() < at) std::this_thread::yield();
      control.request_cancel();
    });
    try {
      signed_distance_field(mesh, g, o, &control);
      ADD_FAILURE() << "no exception";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::cancelled);
      EXPECT_LT(control.progress(), 1.0);
    }
    stop = true;
    canceller.join();
  }
}

// The band slab by slab: the whole field's bits for both conventions, both
// units, band widths, thread counts and grids whose z size is no multiple of
// the chunk; the solid handed on is the parity solid; slabs come in order.
TEST(SignedDistanceFieldSlabs, SlabsAreTheWholeFieldBitForBit) {
  const Mesh mesh = mixed_mesh();
  for (const std::int64_t nz : {std::int64_t{30}, std::int64_t{37}, std::int64_t{5}}) {
    const Grid g = make_grid({-7.3, -7.1, -4.2}, 0.3 * 30.0 / static_cast<double>(nz), 50, 48, nz);
    for (const SignConvention sign : {SignConvention::inside_negative, SignConvention::inside_positive})
      for (const bool model_units : {true, false})
        for (const auto& [band, threads] : {std::pair{3.0, 2}, std::pair{1.5, 1}, std::pair{6.0, 5}}) {
          SCOPED_TRACE("nz " + std::to_string(nz) + " " + to_string(sign) + (model_units ? " model" : " voxels") +
                       " band " + std::to_string(band) + " threads " + std::to_string(threads));
          SdfOptions o;
          o.sign = sign;
          o.model_units = model_units;
          o.band = band;
          o.threads = threads;
          BitVolume expected_solid;
          const DenseVolume<float> expected = signed_distance_field(mesh, g, o, nullptr, &expected_solid);
          DenseVolume<float> got(g, std::nanf(""));
          BitVolume solid(g);
          std::int64_t next_solid = 0, next_values = 0;
          signed_distance_field_slabs(
              mesh, g, o,
              [&](std::int64_t k0, const RunSlab& runs) {
                EXPECT_EQ(k0, next_solid);
                const BitVolume bits = runs.to_bits();
                std::memcpy(solid.slab(k0), bits.data(), bits.byte_size());
                next_solid = k0 + runs.grid().dims.z;
              },
              [&](std::int64_t k0, const ValueVolume& slab) {
                EXPECT_EQ(k0, next_values);
                const auto& v = std::get<DenseVolume<float>>(slab);
                EXPECT_DOUBLE_EQ(v.grid().origin.z, g.origin.z + static_cast<double>(k0) * g.voxel_size);
                std::memcpy(got.slab(k0), v.values().data(), v.values().size() * sizeof(float));
                next_values = k0 + v.grid().dims.z;
              });
          EXPECT_EQ(next_solid, nz);
          EXPECT_EQ(next_values, nz);
          EXPECT_EQ(std::memcmp(got.values().data(), expected.values().data(), got.values().size() * sizeof(float)), 0);
          EXPECT_EQ(std::memcmp(solid.data(), expected_solid.data(), solid.byte_size()), 0);
        }
  }
}

TEST(SignedDistanceFieldSlabs, RefusesWhatNeedsTheWholeGridAndClampsAnEmptyMesh) {
  const Grid g = make_grid({-1, -1, -1}, 0.5, 6, 5, 4);
  SdfOptions full, vote;
  full.full = true;
  vote.inside = InsideTest::vote;
  for (const SdfOptions& o : {full, vote}) {
    ASSERT_TRUE(sdf_slabs_refusal(o).has_value());
    try {
      signed_distance_field_slabs(mesh_of_box(), g, o, [](std::int64_t, const RunSlab&) {},
                                  [](std::int64_t, const ValueVolume&) {});
      ADD_FAILURE() << "accepted: " << *sdf_slabs_refusal(o);
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::invalid_argument);
      EXPECT_EQ(e.what(), *sdf_slabs_refusal(o));
    }
  }
  EXPECT_NE(sdf_slabs_refusal(vote)->find("vote"), std::string::npos);
  std::uint64_t values = 0;
  signed_distance_field_slabs(Mesh{}, g, {}, [](std::int64_t, const RunSlab& runs) { EXPECT_EQ(runs.count(), 0u); },
                              [&](std::int64_t, const ValueVolume& slab) {
                                for (const float v : std::get<DenseVolume<float>>(slab).values()) {
                                  EXPECT_EQ(v, 1.5f);
                                  ++values;
                                }
                              });
  EXPECT_EQ(values, g.voxel_count());
}

TEST(SignedDistanceField, MeshWithoutTrianglesIsClampedEverywhere) {
  const Grid g = make_grid({-1, -1, -1}, 0.5, 6, 5, 4);
  for (const bool full : {false, true}) {
    SdfOptions o;
    o.full = full;
    const DenseVolume<float> sdf = signed_distance_field(Mesh{}, g, o);
    for (const float v : sdf.values()) ASSERT_EQ(v, 1.5f);
  }
}

TEST(SignedDistanceField, RejectsBadBand) {
  const Mesh mesh = test::make_box({0, 0, 0}, {1, 1, 1});
  const Grid g = make_grid({-1, -1, -1}, 0.5, 6, 6, 6);
  for (const double band : {0.0, -1.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    SdfOptions o;
    o.band = band;
    try {
      signed_distance_field(mesh, g, o);
      ADD_FAILURE() << "band " << band << " accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::invalid_argument);
    }
  }
}

}  // namespace
}  // namespace voxd
