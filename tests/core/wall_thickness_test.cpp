// Wall thickness against parts built in code with known walls, and the
// feature transform it rests on against brute force.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <glm/common.hpp>

#include "support/ray_thickness.h"
#include "support/test_meshes.h"
#include "support/test_parts.h"
#include "support/wall_parts.h"
#include "voxd/analysis/analysis.h"
#include "voxd/analysis/distance_transform.h"
#include "voxd/mesh_io/mesh_decode.h"
#include "voxd/analysis/surface_thickness.h"
#include "voxd/analysis/wall_thickness.h"
#include "voxd/mesh_report.h"
#include "voxd/detail/bit_window.h"
#include "voxd/detail/nearest_empty.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd {
namespace {

using test::solid_of;

struct Range {
  double min = 1e30, max = 0.0;
  std::uint64_t voxels = 0;
};
// Over the filled voxels whose centre satisfies `where` (model units).
template <typename Where>
Range range_of(const BitVolume& solid, const DenseVolume<float>& t, Where where) {
  Range r;
  const Grid& g = solid.grid();
  for (std::int64_t k = 0; k < g.dims.z; ++k)
    for (std::int64_t j = 0; j < g.dims.y; ++j)
      for (std::int64_t i = 0; i < g.dims.x; ++i) {
        if (!solid.get(i, j, k)) continue;
        if (!where(g.origin + (glm::dvec3(i, j, k) + 0.5) * g.voxel_size)) continue;
        const double v = t.at(i, j, k) * g.voxel_size;
        r.min = std::min(r.min, v);
        r.max = std::max(r.max, v);
        ++r.voxels;
      }
  return r;
}
Range range_of(const BitVolume& solid, const DenseVolume<float>& t) {
  return range_of(solid, t, [](const glm::dvec3&) { return true; });
}

// A plate T thick (z), W wide (x), D deep (y), centred on the origin, its
// two long edges chamfered by c at 45° (0: sharp). Its ends stay sharp.
Mesh plate(double T, double W, double D, double c) {
  std::vector<glm::dvec2> o;
  if (c > 0) {
    o = {{c, 0}, {W - c, 0}, {W, c}, {W, T - c}, {W - c, T}, {c, T}, {0, T - c}, {0, c}};
  } else {
    o = {{0, 0}, {W, 0}, {W, T}, {0, T}};
  }
  Mesh m = test::make_extrusion(o, 0, D);
  for (auto& v : m.vertices) v -= glm::vec3(static_cast<float>(W / 2), static_cast<float>(D / 2), static_cast<float>(T / 2));
  return m;
}

TEST(PaddedIndex, DecodesEveryIndexItMakesUpToThe32BitLimit) {
  // The decode divides by multiplying; it must be exact for every 32-bit
  // index, so grids of small, odd, power-of-two and the largest accepted
  // sizes, at their corners and at random voxels.
  std::mt19937_64 rng(3);
  for (const glm::i64vec3 dims : {glm::i64vec3{1, 1, 1}, glm::i64vec3{62, 30, 7}, glm::i64vec3{126, 254, 510},
                                  glm::i64vec3{1620, 1620, 1630}, glm::i64vec3{65533, 21843, 1}}) {
    const detail::PaddedIndex padded(test::unit_grid(dims));
    ASSERT_LE(static_cast<double>(padded.px) * padded.py * padded.pz, 4294967296.0);
    std::vector<glm::i64vec3> points;
    for (int c = 0; c < 8; ++c)
      points.push_back({c & 1 ? dims.x : -1, c & 2 ? dims.y : -1, c & 4 ? dims.z : -1});
    for (int n = 0; n < 100000; ++n)
      points.push_back({static_cast<std::int64_t>(rng() % (dims.x + 2)) - 1,
                        static_cast<std::int64_t>(rng() % (dims.y + 2)) - 1,
                        static_cast<std::int64_t>(rng() % (dims.z + 2)) - 1});
    for (const glm::i64vec3& p : points) ASSERT_EQ(padded.at(padded.of(p.x, p.y, p.z)), p) << dims.x << " " << p.x;
  }
}

TEST(BitWindow5, IsTheVolumesBitsAroundEveryVoxelAndNothingOutside) {
  // Rows of 61 to 131 voxels: windows inside one word, across two (the
  // window's first bit at 60 to 63 of a word), and by both edges of x, y, z.
  std::mt19937 rng(5);
  for (std::int64_t nx : {61, 64, 67, 126, 131}) {
    const Grid g = test::unit_grid(nx, 6, 5);
    BitVolume v(g);
    std::bernoulli_distribution fill(0.5);
    for (std::int64_t k = 0; k < g.dims.z; ++k)
      for (std::int64_t j = 0; j < g.dims.y; ++j)
        for (std::int64_t i = 0; i < g.dims.x; ++i) v.set(i, j, k, fill(rng));
    for (std::int64_t k = -1; k <= g.dims.z; ++k)
      for (std::int64_t j = -1; j <= g.dims.y; ++j)
        for (std::int64_t i = -1; i <= g.dims.x; ++i) {
          const detail::BitWindow5 w(v, {i, j, k});
          for (int z = -2; z <= 2; ++z)
            for (int y = -2; y <= 2; ++y)
              for (int x = -2; x <= 2; ++x) {
                const std::int64_t a = i + x, b = j + y, c = k + z;
                const bool inside = a >= 0 && b >= 0 && c >= 0 && a < g.dims.x && b < g.dims.y && c < g.dims.z;
                ASSERT_EQ(w.get(x, y, z), inside && v.get(a, b, c)) << nx << ": " << i << " " << j << " " << k << " + "
                                                                    << x << " " << y << " " << z;
              }
        }
  }
}

TEST(NearestEmpty, IsAnEmptyVoxelAtTheDistanceTransformsDistance) {
  // Dense fills, and (from trial 6) fills inside a box of the grid whose
  // corners vary, with empty voxels around it: passes y and z read only
  // from the voxel before the first filled one of a line to the one after
  // its last, and may not miss a boundary.
  std::mt19937 rng(7);
  for (int trial = 0; trial < 14; ++trial) {
    const Grid g = test::unit_grid(13 + trial % 6 + (trial >= 6 ? 20 : 0), 11, 9 + trial % 3);
    BitVolume v(g);
    std::bernoulli_distribution fill(trial % 2 ? 0.9 : 0.7);
    glm::i64vec3 lo{0}, hi = g.dims;
    if (trial >= 6)
      for (int a = 0; a < 3; ++a) {
        lo[a] = static_cast<std::int64_t>(rng() % 3);
        hi[a] = g.dims[a] - static_cast<std::int64_t>(rng() % 3);
      }
    for (std::int64_t k = lo.z; k < hi.z; ++k)
      for (std::int64_t j = lo.y; j < hi.y; ++j)
        for (std::int64_t i = lo.x; i < hi.x; ++i) v.set(i, j, k, fill(rng));
    const auto nearest = detail::nearest_empty_voxels(v, 1 + trial % 2);
    const auto d2 = squared_distance_transform(v, 1);
    const detail::PaddedIndex padded(g);
    for (std::int64_t k = 0; k < g.dims.z; ++k)
      for (std::int64_t j = 0; j < g.dims.y; ++j)
        for (std::int64_t i = 0; i < g.dims.x; ++i) {
          const glm::i64vec3 f = padded.at(nearest.at(i, j, k));
          if (!v.get(i, j, k)) {
            ASSERT_EQ(f, glm::i64vec3(i, j, k));
            continue;
          }
          const bool outside = f.x < 0 || f.y < 0 || f.z < 0 || f.x >= g.dims.x || f.y >= g.dims.y || f.z >= g.dims.z;
          ASSERT_TRUE(outside || !v.get(f.x, f.y, f.z)) << i << " " << j << " " << k;
          const glm::i64vec3 e = f - glm::i64vec3(i, j, k);
          ASSERT_EQ(static_cast<std::uint32_t>(e.x * e.x + e.y * e.y + e.z * e.z), d2.at(i, j, k)) << i << " " << j << " " << k;
        }
  }
}

TEST(NearestMarked, IsAMarkedVoxelAtTheBruteForceDistanceAndNoneWithoutOne) {
  // Sparse and dense marks, a grid with none, and marks in one or two
  // layers only (as a wall's medial voxels may be: the passes skip the
  // layers with none): the outside is never a mark, so a voxel's nearest
  // mark may lie far across the grid.
  std::mt19937 rng(11);
  for (int trial = 0; trial < 8; ++trial) {
    const Grid g = test::unit_grid(12 + trial, 9, 7 + trial % 3);
    BitVolume marked(g);
    std::bernoulli_distribution mark(trial == 0 ? 0.0 : trial % 2 ? 0.02 : 0.3);
    std::vector<glm::i64vec3> marks;
    for (std::int64_t k = 0; k < g.dims.z; ++k)
      for (std::int64_t j = 0; j < g.dims.y; ++j)
        for (std::int64_t i = 0; i < g.dims.x; ++i)
          if (mark(rng) && (trial < 6 || k == (trial == 6 ? 3 : 0) || (trial == 7 && k == g.dims.z - 1))) {
            marked.set(i, j, k, true);
            marks.push_back({i, j, k});
          }
    // Written over a volume that held something else.
    DenseVolume<std::uint32_t> nearest(g, 12345u);
    detail::nearest_marked_voxels(marked, nearest, nullptr, 1 + trial % 2);
    // Wanted only in a ball and a few scattered voxels, none in rows 0 and 8
    // (the last pass skips those rows' lines): the wanted voxels get the
    // same answer as without it.
    BitVolume wanted(g);
    for (std::int64_t k = 0; k < g.dims.z; ++k)
      for (std::int64_t j = 0; j < g.dims.y; ++j)
        for (std::int64_t i = 0; i < g.dims.x; ++i)
          wanted.set(i, j, k, (i - 4) * (i - 4) + (j - 4) * (j - 4) + (k - 3) * (k - 3) <= 9 || (j == 6 && (i + k) % 5 == 0));
    DenseVolume<std::uint32_t> nearest_wanted(g, 777u);
    detail::nearest_marked_voxels(marked, nearest_wanted, &wanted, 1 + trial % 2);
    const detail::PaddedIndex padded(g);
    std::int64_t skipped = 0;
    for (std::int64_t k = 0; k < g.dims.z; ++k)
      for (std::int64_t j = 0; j < g.dims.y; ++j)
        for (std::int64_t i = 0; i < g.dims.x; ++i) {
          const glm::i64vec3 p{i, j, k};
          if (wanted.get(i, j, k)) {
            ASSERT_EQ(nearest_wanted.at(i, j, k), nearest.at(i, j, k)) << i << " " << j << " " << k;
          } else {
            skipped += nearest_wanted.at(i, j, k) != nearest.at(i, j, k);
          }
          if (marks.empty()) {
            ASSERT_EQ(nearest.at(i, j, k), detail::kNoNearestVoxel);
            continue;
          }
          // Of the nearest marks, the first in memory order (lowest z, then
          // y, then x): each pass keeps the earlier of two equally near
          // sites along its axis, so the answer does not depend on how the
          // passes are cut (wall thickness's results are the same bytes).
          std::int64_t best = INT64_MAX;
          glm::i64vec3 first{0};
          for (const glm::i64vec3& m : marks) {  // in memory order
            const glm::i64vec3 e = m - p;
            if (e.x * e.x + e.y * e.y + e.z * e.z < best) {
              best = e.x * e.x + e.y * e.y + e.z * e.z;
              first = m;
            }
          }
          ASSERT_NE(nearest.at(i, j, k), detail::kNoNearestVoxel);
          const glm::i64vec3 f = padded.at(nearest.at(i, j, k));
          ASSERT_EQ(f, first) << trial << ": " << i << " " << j << " " << k;
          ASSERT_TRUE(marked.get(f.x, f.y, f.z)) << i << " " << j << " " << k;
        }
    // The skipped lines are really skipped (their voxels keep pass y's
    // nearest within their layer), where some voxel has a mark to find.
    if (!marks.empty()) {
      EXPECT_GT(skipped, 0) << trial;
    }
  }
}

TEST(WallThickness, AxisAlignedPlateIsExactlyItsVoxelCount) {
  // 1.0 / 0.1 = 10 voxels, 1.0 / 0.2 = 5, 1.0 / 0.13 = 7.7 -> 8 voxels once
  // voxelized: the report is the voxel model's wall, sharp or chamfered.
  for (double voxel : {0.1, 0.13, 0.2})
    for (double chamfer : {0.0, 0.3}) {
      const BitVolume v = solid_of(plate(1.0, 6, 5, chamfer), voxel);
      const Range r = range_of(v, wall_thickness(v, 2));
      const double n = std::round(1.0 / voxel) * voxel;
      EXPECT_NEAR(r.min, n, 1e-5) << voxel << " " << chamfer;
      EXPECT_NEAR(r.max, n, 1e-5) << voxel << " " << chamfer;
    }
}

TEST(WallThickness, TiltedPlateIsWithinAVoxelEverywhere) {
  // Rotated 30° about x and y: every voxel, edges and corners included,
  // within one voxel of the plate's thickness; no edge reads as thin.
  for (double voxel : {0.1, 0.13, 0.2})
    for (double chamfer : {0.0, 0.3}) {
      const BitVolume v = solid_of(test::rotated(plate(1.0, 6, 5, chamfer), 30, 30), voxel);
      const Range r = range_of(v, wall_thickness(v, 2));
      EXPECT_GT(r.min, 1.0 - voxel) << voxel << " " << chamfer;
      EXPECT_LT(r.max, 1.0 + voxel) << voxel << " " << chamfer;
    }
}

TEST(WallThickness, TubeAndSphericalShellAreRMinusREverywhere) {
  const double h = 0.1;
  const BitVolume tube = solid_of(test::make_tube(3, 2.2, 0, 5, 256), h);
  const Range t = range_of(tube, wall_thickness(tube, 2));
  EXPECT_GT(t.min, 0.8 - h);
  EXPECT_LT(t.max, 0.8 + h);
  const BitVolume shell = solid_of(
      test::concat({test::make_icosphere({0, 0, 0}, 3, 5), test::flipped(test::make_icosphere({0, 0, 0}, 2.3, 5))}), h);
  const Range s = range_of(shell, wall_thickness(shell, 2));
  EXPECT_GT(s.min, 0.7 - h);
  EXPECT_LT(s.max, 0.7 + h);
}

// Curved walls many voxels thick against the mesh's own ray thickness
// (support/ray_thickness.h), at points on the walls' faces 2 voxels or more
// from a sharp edge: a tube 30 voxels thick along a grid axis, whose faces
// cross the axes at every angle (it read up to 2 voxels low 3-14° off an
// axis, where a surface fit leant towards the staircase's risers), and a
// spherical shell turned off the grid. Every point within a voxel, and the
// report finds no thin region with min_wall one voxel under the wall.
// Issue #35's acceptance on the generated parts of tests/support/
// wall_parts.h at 0.05 mm voxels (walls 16 to 60 voxels: tubes, shells, a
// cup, a drafted sleeve, a boss, filleted ribs, most turned off the grid):
// 99% of surface points read within a voxel of the mesh's own ray
// thickness (99.9% within 1.5), and the report passes the part at min_wall
// one voxel under its thinnest wall and fails it one voxel over, with that
// wall as the thin region; and 95% of its vertices off sharp edges read
// within a voxel of the ray at them.
class CurvedWallPart : public ::testing::TestWithParam<std::size_t> {};

TEST_P(CurvedWallPart, ReadsItsRayThicknessWithinAVoxelAndPassesOrFailsMinWallByAVoxel) {
  const double h = 0.05;
  const test::WallPart part = test::curved_wall_parts().at(GetParam());
  SCOPED_TRACE(part.name);
  const BitVolume v = solid_of(part.mesh, h);
  const DenseVolume<float> map = wall_thickness(v, 2);
  const test::WallAgreement w = test::compare_with_rays(part.mesh, v, map, 1000);
  EXPECT_GE(w.points, 1000u);
  EXPECT_GE(w.within_1, 0.99) << "p1 " << w.p01 << ", p99 " << w.p99;
  // Known limit: on the straight rib, the plate's face within a fillet's
  // first segment (7.5° off the plate) of the rib's root reads the section
  // a little further into the fillet, up to 5 voxels over its ray (thicker,
  // never thinner): 0.2% of its points.
  EXPECT_GE(w.within_1_5, part.name.starts_with("straight rib") ? 0.997 : 0.999);
  EXPECT_NEAR(w.ray_min, part.wall, 0.01);  // the reference finds the part's thinnest wall
  AnalysisOptions options;
  options.skin = false;
  options.thickness_map = &map;
  options.min_wall_voxels = part.wall / h - 1.0;
  EXPECT_TRUE(analyze_volume(v, options).thickness->thin_regions.empty());
  options.min_wall_voxels = part.wall / h + 1.0;
  const AnalysisReport fails = analyze_volume(v, options);
  ASSERT_FALSE(fails.thickness->thin_regions.empty());
  const ThicknessRegion& worst = fails.thickness->thin_regions.front();
  EXPECT_NEAR(worst.extreme_thickness, part.wall / h, 1.0);
  std::uint64_t thin = 0;
  for (const ThicknessRegion& r : fails.thickness->thin_regions) thin += r.voxel_count;
  EXPECT_GT(thin, v.count() / 10);  // the wall itself, not a few voxels of it

  // On the part's own vertices (voxd/analysis/surface_thickness.h), those
  // off sharp edges whose ray crosses a wall: 95% within a voxel.
  const Mesh welded = weld_vertices(part.mesh);
  const test::VertexAgreement on_part = test::compare_vertices_with_rays(welded, surface_thickness(welded, map).thickness, h);
  if (!part.name.starts_with("straight rib")) {  // whose vertices are all on its edges
    EXPECT_GE(on_part.vertices, 100u);
    EXPECT_GE(on_part.within_1, 0.95) << on_part.vertices << " vertices";
  }
}

INSTANTIATE_TEST_SUITE_P(Parts, CurvedWallPart, ::testing::Range<std::size_t>(0, test::curved_wall_parts().size()));

TEST(WallThickness, LBracketFinIsThinAndTheWallsAreNot) {
  // Base 3 mm (z), upright 2 mm (x), a 0.6 mm fin on the base at x 12..12.6,
  // 5 mm tall, all 15 mm deep (y). The fin is 0.6 and everything else its
  // own wall, right up to the part's end faces.
  const double h = 0.1;
  const Mesh l = test::make_extrusion(
      {{0, 0}, {20, 0}, {20, 3}, {12.6, 3}, {12.6, 8}, {12, 8}, {12, 3}, {2, 3}, {2, 20}, {0, 20}}, 0, 15);
  const BitVolume v = solid_of(l, h);
  const DenseVolume<float> w = wall_thickness(v, 2);
  const Range all = range_of(v, w);
  EXPECT_NEAR(all.max, 3.0, h);
  const Range fin = range_of(v, w, [&](const glm::dvec3& p) { return p.z > 3.1; });
  const Range fin_only = range_of(v, w, [&](const glm::dvec3& p) { return p.z > 3.1 && p.x > 11 && p.x < 13.6; });
  EXPECT_NEAR(fin_only.min, 0.6, h);
  EXPECT_NEAR(fin_only.max, 0.6, h);
  // Above the base, the upright (2 mm) and the fin only. Where the upright
  // stands on the base, within 0.5 mm of an end face, the junction's
  // fringe reads the base's 3 mm for up to 0.35 mm above the base (the
  // thicker wall owns the root).
  EXPECT_GT(fin.min, 0.6 - h);
  const Range upright = range_of(v, w, [&](const glm::dvec3& p) { return p.z > 3.4 && p.x < 2 && p.z < 19; });
  EXPECT_NEAR(upright.min, 2.0, h);
  EXPECT_NEAR(upright.max, 2.0, h);
  // The base, up to the voxel under the fin's root: 3 mm, not the fin's 0.6.
  const Range base = range_of(v, w, [&](const glm::dvec3& p) { return p.z < 3 - h && p.x > 2.5; });
  EXPECT_NEAR(base.min, 3.0, h);
  EXPECT_NEAR(base.max, 3.0, h);
  // What is under 0.8 mm is the fin: its box within a voxel of the fin's.
  const Grid& g = v.grid();
  glm::dvec3 lo(1e30), hi(-1e30);
  for (std::int64_t k = 0; k < g.dims.z; ++k)
    for (std::int64_t j = 0; j < g.dims.y; ++j)
      for (std::int64_t i = 0; i < g.dims.x; ++i) {
        if (!v.get(i, j, k) || w.at(i, j, k) * h >= 0.8) continue;
        lo = glm::min(lo, g.origin + glm::dvec3(i, j, k) * h);
        hi = glm::max(hi, g.origin + (glm::dvec3(i, j, k) + 1.0) * h);
      }
  const glm::dvec3 fin_lo(12, 0, 3), fin_hi(12.6, 15, 8);
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(lo[a], fin_lo[a], h + 1e-9) << a;
    EXPECT_NEAR(hi[a], fin_hi[a], h + 1e-9) << a;
  }
}

// A point of the grid (model units) back in the frame of a part that
// test::rotated() turned by ax about x, then ay about y.
glm::dvec3 unrotated(const glm::dvec3& p, double ax_degrees, double ay_degrees) {
  const double ax = ax_degrees * 3.14159265358979323846 / 180.0, ay = ay_degrees * 3.14159265358979323846 / 180.0;
  const glm::dvec3 q{p.x * std::cos(ay) - p.z * std::sin(ay), p.y, p.x * std::sin(ay) + p.z * std::cos(ay)};
  return {q.x, q.y * std::cos(ax) + q.z * std::sin(ax), -q.y * std::sin(ax) + q.z * std::cos(ax)};
}

TEST(WallThickness, WedgeIsThinExactlyWhereItsThicknessCrossesMinWall) {
  // A symmetric wedge, 2 mm thick at x = 0 tapering to 0 at x = L (its
  // faces 2 atan(1/L) apart, a wall, not an edge), 4 mm deep (y), turned
  // off the grid. Its section across its mid-plane is t(x) = 2 (1 - x / L),
  // so it is thinner than min_wall exactly where x > x* = L (1 - min_wall / 2).
  // The region of voxels that read thinner than min_wall, as voxel cubes,
  // must end within a voxel of the plane x = x*: a voxel on the wrong side
  // is at most a voxel (plus its own half-extent along x) from it. Within
  // the wall's end zones (up to half its thickness from its end faces
  // y = +-2, where the medial surface has stopped and the voxels take the
  // nearest point of its ragged edge, which may lie a few voxels along the
  // taper), within four voxels (three measured). (Along the grid a taper
  // this gentle is a staircase in the voxel model: see the header's limits.)
  const double h = 0.1;
  for (double L : {5.0, 8.0})
    for (const auto& [ax, ay] : {std::pair{30.0, 30.0}, std::pair{20.0, -35.0}}) {
      const BitVolume v = solid_of(test::rotated(test::make_extrusion({{0, -1}, {L, 0}, {0, 1}}, -2, 2), ax, ay), h);
      const DenseVolume<float> w = wall_thickness(v, 2);
      const Grid& g = v.grid();
      // A voxel cube's half-extent along the wedge's x axis.
      const glm::dvec3 o = unrotated(glm::dvec3(0.0), ax, ay);
      const double half_extent = 0.5 * h *
                                 (std::abs(unrotated({1, 0, 0}, ax, ay).x - o.x) + std::abs(unrotated({0, 1, 0}, ax, ay).x - o.x) +
                                  std::abs(unrotated({0, 0, 1}, ax, ay).x - o.x));
      for (double min_wall : {0.6, 0.8, 1.2}) {
        const double crossing = L * (1.0 - min_wall / 2.0);
        double worst_inside = 0.0, worst_end = 0.0;
        for (std::int64_t k = 0; k < g.dims.z; ++k)
          for (std::int64_t j = 0; j < g.dims.y; ++j)
            for (std::int64_t i = 0; i < g.dims.x; ++i) {
              if (!v.get(i, j, k)) continue;
              const glm::dvec3 p = unrotated(g.origin + (glm::dvec3(i, j, k) + 0.5) * h, ax, ay);
              const bool thin = w.at(i, j, k) * h < min_wall;
              if (thin == (p.x > crossing)) continue;
              const double off = std::abs(p.x - crossing) - half_extent;
              double& worst = std::abs(p.y) > 2.0 - min_wall / 2 - h ? worst_end : worst_inside;
              worst = std::max(worst, off);
            }
        EXPECT_LE(worst_inside, h) << "L " << L << " turned " << ax << " " << ay << " min_wall " << min_wall;
        EXPECT_LE(worst_end, 4 * h) << "L " << L << " turned " << ax << " " << ay << " min_wall " << min_wall;
      }
    }
}

TEST(WallThickness, SameResultOnOneThreadAndMany) {
  const BitVolume v = solid_of(test::rotated(plate(1.0, 4, 3, 0.3), 30, 30), 0.1);
  EXPECT_TRUE(wall_thickness(v, 1).values() == wall_thickness(v, 3).values());
}

TEST(WallThickness, ErrorStatementGivesVoxelsAndModelUnits) {
  const std::string s = wall_thickness_error_statement(0.25);
  EXPECT_NE(s.find("-1 to +1 voxels (-0.25 to +0.25 model units)"), std::string::npos) << s;
}

// The report: thin regions of the wall thickness, as the service and the
// CLI give them.
ThicknessAnalysis thin_walls(const BitVolume& v, double min_wall) {
  AnalysisOptions o;
  o.skin = false;
  o.threads = 2;
  o.min_wall_voxels = min_wall / v.grid().voxel_size;
  return *analyze_volume(v, o).thickness;
}

TEST(ThinWallReport, APlateOfAnyOrientationHasNoThinRegionAndIsOneWhenThinnerThanMinWall) {
  // No thin region while T >= min_wall, sharp or chamfered, along the grid
  // or turned 30° about two axes (a wall reads within a tenth of a voxel of
  // T on flat faces, and the report allows a quarter); the whole plate one
  // region once min_wall > T + 1 voxel.
  for (double voxel : {0.1, 0.13, 0.2})
    for (double chamfer : {0.0, 0.3})
      for (bool tilted : {false, true}) {
        const Mesh m = plate(1.0, 6, 5, chamfer);
        const BitVolume v = solid_of(tilted ? test::rotated(m, 30, 30) : m, voxel);
        // The voxel model of a plate 1.0 thick at 0.13 is 8 voxels, 1.04.
        const double t = tilted ? 1.0 : std::round(1.0 / voxel) * voxel;
        const ThicknessAnalysis pass = thin_walls(v, t);
        EXPECT_TRUE(pass.thin_regions.empty()) << voxel << " " << chamfer << " " << tilted;
        EXPECT_NEAR(pass.stats.min * voxel, t, 0.1 * voxel) << voxel << " " << chamfer << " " << tilted;
        EXPECT_NEAR(pass.stats.max * voxel, t, 0.1 * voxel) << voxel << " " << chamfer << " " << tilted;
        const ThicknessAnalysis fail = thin_walls(v, 1.0 + 1.5 * voxel);
        ASSERT_EQ(fail.thin_regions.size(), 1u) << voxel << " " << chamfer << " " << tilted;
        EXPECT_EQ(fail.thin_regions[0].voxel_count, v.count());
      }
}

// The verdict with the error bound (one voxel): a plate T thick, along the
// grid or turned 30° about two axes, against min_wall = T + k voxels. Under
// by 3 voxels: fail; within a voxel either side: inconclusive, naming the
// voxel that would decide it; over by a voxel or more: pass.
TEST(ThinWallReport, TheVerdictIsPassFailOrInconclusiveWithinTheErrorBound) {
  struct Case {
    double k;
    ThicknessVerdict verdict;
  };
  const Case cases[] = {{-3, ThicknessVerdict::pass},          {-1, ThicknessVerdict::pass},
                        {-0.5, ThicknessVerdict::inconclusive}, {0.5, ThicknessVerdict::inconclusive},
                        {1, ThicknessVerdict::inconclusive},    {3, ThicknessVerdict::fail}};
  for (double voxel : {0.1, 0.13})
    for (bool tilted : {false, true}) {
      const Mesh m = plate(1.0, 6, 5, 0.0);
      const BitVolume v = solid_of(tilted ? test::rotated(m, 30, 30) : m, voxel);
      const double t = tilted ? 1.0 : std::round(1.0 / voxel) * voxel;
      for (const Case& c : cases) {
        const ThicknessAnalysis a = thin_walls(v, t + c.k * voxel);
        EXPECT_EQ(thickness_verdict(a), c.verdict) << voxel << " " << tilted << " k " << c.k;
        const std::optional<double> decide = deciding_voxel_size(a);
        EXPECT_EQ(decide.has_value(), c.verdict == ThicknessVerdict::inconclusive);
        // The plate reads T: decided once the bound and the tolerance
        // (1.25 voxels) fit between T and min_wall, by a wall of at most 20 voxels.
        if (decide) {
          const double expected = std::max(std::abs(c.k) / 1.25, a.min_wall_voxels / 20.0);
          EXPECT_NEAR(*decide, expected, 0.1) << voxel << " " << tilted << " k " << c.k;
        }
      }
    }
}

TEST(ThinWallReport, TheLBracketsOnlyThinRegionIsTheFin) {
  const double h = 0.1;
  const BitVolume v = solid_of(test::make_extrusion({{0, 0}, {20, 0}, {20, 3}, {12.6, 3}, {12.6, 8}, {12, 8}, {12, 3},
                                                     {2, 3}, {2, 20}, {0, 20}},
                                                    0, 15),
                               h);
  const ThicknessAnalysis t = thin_walls(v, 0.8);
  EXPECT_NEAR(t.stats.max * h, 3.0, h);
  ASSERT_EQ(t.thin_regions.size(), 1u);
  const ThicknessRegion& fin = t.thin_regions[0];
  EXPECT_NEAR(fin.extreme_thickness * h, 0.6, h);
  EXPECT_NEAR(fin.mean_thickness * h, 0.6, h);
  const Grid& g = v.grid();
  const glm::dvec3 lo = g.origin + glm::dvec3(fin.bbox_min) * h, hi = g.origin + glm::dvec3(fin.bbox_max + glm::i64vec3(1)) * h;
  const glm::dvec3 fin_lo(12, 0, 3), fin_hi(12.6, 15, 8);
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(lo[a], fin_lo[a], h + 1e-9) << a;
    EXPECT_NEAR(hi[a], fin_hi[a], h + 1e-9) << a;
  }
}

// The parts of test_parts.h: their edges, thread crests and flanks are
// edges of a wall, never walls; what is measured is the closed form's wall.
TEST(ThinWallReport, CadPartsHaveNoThinRegionFromTheirEdges) {
  // A thin hex nut (a plate 1.2 mm thick with a 2.5 mm bore) at 0.02 mm
  // voxels: under local thickness its edges made "thin" regions; its wall is
  // its height everywhere.
  const test::Part nut = test::make_hex_nut();
  const BitVolume nut_voxels = solid_of(nut.mesh, 0.02);
  const ThicknessAnalysis n = thin_walls(nut_voxels, 0.5);
  EXPECT_TRUE(n.thin_regions.empty()) << n.thin_regions.size();
  // Within a voxel (a face on a row of voxel centres adds one).
  EXPECT_LE(std::abs(n.stats.min * 0.02 - nut.thinnest_wall), 0.02 + 1e-9);
  EXPECT_LE(std::abs(n.stats.max * 0.02 - nut.largest_ball), 0.02 + 1e-9);
  // The screw: its head and core are never thin, and nothing reads thicker
  // than its largest ball. Its thread's teeth, turned into rings here, are
  // read as thin walls by today's analysis (ring fins of 60-degree flanks;
  // a helical thread from outside the repository was not): that is the
  // curved-wall reading issue #35 takes on, so only the shank may hold thin
  // regions.
  const test::Part screw = test::make_screw();
  const BitVolume screw_voxels = solid_of(screw.mesh, 0.04);
  const ThicknessAnalysis s = thin_walls(screw_voxels, 0.5);
  for (const ThicknessRegion& thin : s.thin_regions)
    EXPECT_LT(screw_voxels.grid().origin.z + static_cast<double>(thin.bbox_max.z) * 0.04, 10.0);
  EXPECT_LT(s.stats.max * 0.04, screw.largest_ball + 0.04);
  // The torus, a round bar 5.66 mm across: its diameter at most, and never
  // thin. A bar has no parallel faces: with 28 voxels across, chords a
  // little off its centre read up to 3 voxels short.
  const test::Part torus = test::make_torus_part();
  const BitVolume torus_voxels = solid_of(torus.mesh, 0.2);
  const ThicknessAnalysis r = thin_walls(torus_voxels, 0.5);
  EXPECT_TRUE(r.thin_regions.empty());
  EXPECT_GT(r.stats.min * 0.2, torus.thinnest_wall - 3 * 0.2);
  EXPECT_LT(r.stats.max * 0.2, torus.thinnest_wall + 0.2);
}

}  // namespace
}  // namespace voxd
