// Solid (parity, vote) and surface voxelization against analytic answers and
// independent reference methods.
#include <bit>
#include <cmath>
#include <random>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "support/test_meshes.h"
#include "voxd/error.h"
#include "voxd/grid.h"
#include "voxd/mesh_io/mesh_decode.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd {
namespace {

using test::make_box;
using test::make_icosphere;
using test::make_torus;

// Independent inside test: count crossings of a ray in a fixed irrational
// direction (no ties with axis-aligned or lattice geometry), Moller-Trumbore.
bool inside_by_random_ray(const Mesh& mesh, glm::dvec3 p) {
  const glm::dvec3 dir = glm::normalize(glm::dvec3(0.5772156649, 0.3183098862, 0.7071067812 * 1.1));
  int crossings = 0;
  for (const auto& t : mesh.triangles) {
    const glm::dvec3 a(mesh.vertices[t[0]]), b(mesh.vertices[t[1]]), c(mesh.vertices[t[2]]);
    const glm::dvec3 e1 = b - a, e2 = c - a, pv = glm::cross(dir, e2);
    const double det = glm::dot(e1, pv);
    if (det == 0.0) continue;
    const glm::dvec3 tv = p - a;
    const double u = glm::dot(tv, pv) / det;
    if (u < 0.0 || u > 1.0) continue;
    const glm::dvec3 qv = glm::cross(tv, e1);
    const double v = glm::dot(dir, qv) / det;
    if (v < 0.0 || u + v > 1.0) continue;
    if (glm::dot(e2, qv) / det > 0.0) ++crossings;
  }
  return crossings % 2 == 1;
}

Grid cube_grid(glm::dvec3 origin, double h, std::int64_t n) {
  Grid g;
  g.origin = origin;
  g.voxel_size = h;
  g.dims = {n, n, n};
  return g;
}

TEST(ParityVoxelizer, BoxAwayFromCentresFillsExactlyTheEnclosedCentres) {
  // Faces at quarter-voxel offsets: centres 0.5..7.5 inside [0.25, 7.75] -> 8^3.
  const Mesh box = make_box({0.25, 1.25, 2.25}, {7.75, 6.75, 5.75});
  const Grid g = cube_grid({0, 0, 0}, 1.0, 10);
  for (int axis = 0; axis < 3; ++axis) {
    const BitVolume v = voxelize_parity(box, g, axis, 0, nullptr);
    EXPECT_EQ(v.count(), 8u * 6u * 4u) << "axis " << axis;
    for (std::int64_t k = 0; k < 10; ++k)
      for (std::int64_t j = 0; j < 10; ++j)
        for (std::int64_t i = 0; i < 10; ++i) {
          const bool expected = i <= 7 && j >= 1 && j <= 6 && k >= 2 && k <= 5;
          ASSERT_EQ(v.get(i, j, k), expected) << i << ',' << j << ',' << k;
        }
  }
}

TEST(ParityVoxelizer, IcosphereMatchesIndependentRayCastAtEveryVoxel) {
  const Mesh sphere = make_icosphere({0.1, -0.2, 0.05}, 1.0, 3);
  const Grid g = resolve_grid({GridRequest::Kind::resolution, 24, 0, 1, {}, {}}, bounds(sphere));
  for (int axis = 0; axis < 3; ++axis) {
    const BitVolume v = voxelize_parity(sphere, g, axis, 2, nullptr);
    std::uint64_t mismatches = 0;
    for (std::int64_t k = 0; k < g.dims.z; ++k)
      for (std::int64_t j = 0; j < g.dims.y; ++j)
        for (std::int64_t i = 0; i < g.dims.x; ++i)
          mismatches += v.get(i, j, k) != inside_by_random_ray(sphere, g.center(i, j, k));
    EXPECT_EQ(mismatches, 0u) << "axis " << axis << " filled " << v.count();
  }
}

TEST(ParityVoxelizer, VolumeConvergesToAnalyticVolume) {
  const Mesh sphere = make_icosphere({0, 0, 0}, 1.0, 5);
  const double exact = test::mesh_volume(sphere);
  for (std::int64_t res : {32, 64, 128, 256}) {
    const Grid g = resolve_grid({GridRequest::Kind::resolution, res, 0, 1, {}, {}}, bounds(sphere));
    const BitVolume v = voxelize_parity(sphere, g, 0, 0, nullptr);
    const double vol = static_cast<double>(v.count()) * g.voxel_volume();
    // Centre sampling errs only in voxels cut by the surface, and those errors
    // mostly cancel; a shell of half a voxel over the area bounds it loosely.
    const double area = 4.0 * M_PI;
    EXPECT_NEAR(vol, exact, 0.5 * area * g.voxel_size) << "resolution " << res;
    if (res == 256) {
      EXPECT_NEAR(vol / exact, 1.0, 1e-3);
    }
  }
}

TEST(ParityVoxelizer, ClosedMeshesGiveTheSameVolumeAlongEveryAxis) {
  const Mesh torus = make_torus({0.013, 0.021, -0.007}, 2.0, 0.7, 96, 48);
  const Grid g = resolve_grid({GridRequest::Kind::resolution, 80, 0, 2, {}, {}}, bounds(torus));
  const BitVolume x = voxelize_parity(torus, g, 0, 0, nullptr);
  const BitVolume y = voxelize_parity(torus, g, 1, 0, nullptr);
  const BitVolume z = voxelize_parity(torus, g, 2, 0, nullptr);
  ASSERT_GT(x.count(), 1000u);
  for (std::int64_t k = 0; k < g.dims.z; ++k)
    for (std::int64_t j = 0; j < g.dims.y; ++j)
      for (std::int64_t i = 0; i < g.dims.x; ++i) {
        ASSERT_EQ(x.get(i, j, k), y.get(i, j, k)) << i << ',' << j << ',' << k;
        ASSERT_EQ(x.get(i, j, k), z.get(i, j, k)) << i << ',' << j << ',' << k;
      }
}

// A box whose faces lie exactly on voxel-centre planes, each face tessellated
// so that vertices and edges fall exactly on ray columns: the hardest ties.
Mesh tessellated_box(double lo, double hi, int n) {
  Mesh m;
  auto grid_face = [&](int axis, double fixed, bool outward_positive) {
    const int ua = (axis + 1) % 3, va = (axis + 2) % 3;
    const auto base = static_cast<std::uint32_t>(m.vertices.size());
    for (int b = 0; b <= n; ++b)
      for (int a = 0; a <= n; ++a) {
        glm::dvec3 p;
        p[axis] = fixed;
        p[ua] = lo + (hi - lo) * a / n;
        p[va] = lo + (hi - lo) * b / n;
        m.vertices.emplace_back(p);
      }
    for (int b = 0; b < n; ++b)
      for (int a = 0; a < n; ++a) {
        const std::uint32_t p00 = base + b * (n + 1) + a, p10 = p00 + 1, p01 = p00 + (n + 1), p11 = p01 + 1;
        // (ua, va, axis) is right-handed, so CCW in (ua, va) faces +axis.
        if (outward_positive) {
          m.triangles.push_back({p00, p10, p11});
          m.triangles.push_back({p00, p11, p01});
        } else {
          m.triangles.push_back({p00, p11, p10});
          m.triangles.push_back({p00, p01, p11});
        }
      }
  };
  for (int axis = 0; axis < 3; ++axis) {
    grid_face(axis, lo, false);
    grid_face(axis, hi, true);
  }
  return m;
}

TEST(ParityVoxelizer, FacesOnVoxelCentrePlanesGiveNoStreaksAndExactCounts) {
  // Box [2.5, 12.5]^3 with voxel centres at integer + 0.5: every face lies on
  // a centre plane and every vertex/edge of its 10x10 tessellation on a column.
  const Mesh box = tessellated_box(2.5, 12.5, 10);
  const Grid g = cube_grid({0, 0, 0}, 1.0, 16);
  for (int axis = 0; axis < 3; ++axis) {
    const BitVolume v = voxelize_parity(box, g, axis, 0, nullptr);
    EXPECT_EQ(v.count(), 1000u) << "axis " << axis;
    // Every filled column holds exactly one run of 10: no streaks, no holes.
    for (std::int64_t k = 0; k < 16; ++k)
      for (std::int64_t j = 0; j < 16; ++j) {
        int filled = 0;
        for (std::int64_t i = 0; i < 16; ++i) filled += v.get(i, j, k);
        ASSERT_TRUE(filled == 0 || filled == 10) << "row " << j << ',' << k << " axis " << axis;
      }
  }
}

TEST(ParityVoxelizer, OctahedronWithLatticeVerticesMatchesSymbolicPerturbation) {
  // |x|+|y|+|z| <= 6 around a voxel centre: faces pass through many centres,
  // edges along columns, vertices on centres. The engine treats a centre as
  // displaced by (-delta, +eps, +eps^2) along (ray, u, v), delta >> eps >> eps^2,
  // so a point on a face n.p = c is inside iff the first non-zero of
  // (-n_ray, n_u, n_v) is negative.
  const double r = 6.0;
  const glm::dvec3 c0(10.5, 10.5, 10.5);
  Mesh m;
  for (int s = 0; s < 6; ++s) {
    glm::dvec3 p = c0;
    p[s / 2] += (s % 2 ? -r : r);
    m.vertices.emplace_back(p);
  }
  // vertices: 0:+x 1:-x 2:+y 3:-y 4:+z 5:-z; faces outward CCW.
  const std::uint32_t xs[2] = {0, 1}, ys[2] = {2, 3}, zs[2] = {4, 5};
  for (int sx = 0; sx < 2; ++sx)
    for (int sy = 0; sy < 2; ++sy)
      for (int sz = 0; sz < 2; ++sz) {
        std::array<std::uint32_t, 3> t = {xs[sx], ys[sy], zs[sz]};
        if ((sx + sy + sz) % 2 == 1) std::swap(t[1], t[2]);
        m.triangles.push_back(t);
      }
  ASSERT_GT(test::mesh_volume(m), 0.0);
  const Grid g = cube_grid({0, 0, 0}, 1.0, 21);
  const int uv[3][2] = {{1, 2}, {0, 2}, {0, 1}};
  for (int axis = 0; axis < 3; ++axis) {
    const BitVolume v = voxelize_parity(m, g, axis, 0, nullptr);
    std::uint64_t expected = 0;
    for (std::int64_t k = 0; k < 21; ++k)
      for (std::int64_t j = 0; j < 21; ++j)
        for (std::int64_t i = 0; i < 21; ++i) {
          const glm::dvec3 p = g.center(i, j, k) - c0;
          bool inside = true;
          for (int f = 0; f < 8 && inside; ++f) {
            const glm::dvec3 n((f & 1) ? -1 : 1, (f & 2) ? -1 : 1, (f & 4) ? -1 : 1);
            const double s = glm::dot(n, p);
            if (s > r) inside = false;
            if (s == r) {
              const double key[3] = {-n[axis], n[uv[axis][0]], n[uv[axis][1]]};
              inside = key[0] != 0 ? key[0] < 0 : key[1] != 0 ? key[1] < 0 : key[2] < 0;
            }
          }
          expected += inside;
          ASSERT_EQ(v.get(i, j, k), inside) << i << ',' << j << ',' << k << " axis " << axis;
        }
    EXPECT_GT(expected, 250u);  // 377 lattice points with the boundary, 231 without
  }
}

TEST(ParityVoxelizer, MeshExtendingBeyondTheGridFillsTheCutRuns) {
  // Explicit grid covering only the middle of a long box: rays start inside.
  const Mesh box = make_box({-50.3, 0.2, 0.2}, {100.3, 3.8, 3.8});
  Grid g = cube_grid({0, 0, 0}, 1.0, 4);
  g.dims = {67, 4, 4};  // not a multiple of 64: exercises the row mask
  const BitVolume v = voxelize_parity(box, g, 0, 0, nullptr);
  EXPECT_EQ(v.count(), 67u * 16u);
  // Padding bits past dims.x stay clear.
  EXPECT_EQ(v.row(0, 0)[1] >> 3, 0u);
}

TEST(ParityVoxelizer, HollowSphereCavityIsEmpty) {
  const Mesh hollow = test::concat({make_icosphere({0, 0, 0}, 1.0, 4), test::flipped(make_icosphere({0, 0, 0}, 0.5, 4))});
  const Grid g = resolve_grid({GridRequest::Kind::resolution, 40, 0, 1, {}, {}}, bounds(hollow));
  const BitVolume v = voxelize_parity(hollow, g, 0, 0, nullptr);
  const double vol = static_cast<double>(v.count()) * g.voxel_volume();
  EXPECT_NEAR(vol, test::mesh_volume(hollow), 0.03 * test::mesh_volume(hollow));
  for (std::int64_t k = 0; k < g.dims.z; ++k)
    for (std::int64_t j = 0; j < g.dims.y; ++j)
      for (std::int64_t i = 0; i < g.dims.x; ++i)
        if (glm::length(g.center(i, j, k)) < 0.45) {
          ASSERT_FALSE(v.get(i, j, k));
        }
}

TEST(ParityVoxelizer, ManyThreadsGiveTheSameVolumeAsOne) {
  const Mesh torus = make_torus({0, 0, 0}, 2.0, 0.6, 64, 32);
  const Grid g = resolve_grid({GridRequest::Kind::resolution, 100, 0, 1, {}, {}}, bounds(torus));
  const BitVolume one = voxelize_parity(torus, g, 0, 1, nullptr);
  const BitVolume many = voxelize_parity(torus, g, 0, 7, nullptr);
  ASSERT_EQ(one.word_count(), many.word_count());
  EXPECT_TRUE(std::equal(one.data(), one.data() + one.word_count(), many.data()));
}

TEST(ParityVoxelizer, CancellationStopsWithCancelledError) {
  const Mesh sphere = make_icosphere({0, 0, 0}, 1.0, 3);
  const Grid g = resolve_grid({GridRequest::Kind::resolution, 64, 0, 0, {}, {}}, bounds(sphere));
  JobControl control;
  control.request_cancel();
  try {
    voxelize_parity(sphere, g, 0, 0, &control);
    FAIL() << "expected cancellation";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::cancelled);
  }
}

TEST(ParityVoxelizer, ReportsProgressUpToOne) {
  const Mesh sphere = make_icosphere({0, 0, 0}, 1.0, 3);
  const Grid g = resolve_grid({GridRequest::Kind::resolution, 64, 0, 0, {}, {}}, bounds(sphere));
  JobControl control;
  voxelize_parity(sphere, g, 0, 0, &control);
  EXPECT_DOUBLE_EQ(control.progress(), 1.0);
}

TEST(ParityVoxelizer, IcosphereLevelsConvergeToTheirPolyhedronVolume) {
  // Each subdivision level is a different polyhedron with its own exact
  // volume; at a fixed voxel size the error stays within a thin shell.
  for (int level = 1; level <= 5; ++level) {
    const Mesh sphere = make_icosphere({0.0, 0.0, 0.0}, 1.0, level);
    const double exact = test::mesh_volume(sphere);
    const Grid g = resolve_grid({GridRequest::Kind::resolution, 200, 0, 1, {}, {}}, bounds(sphere));
    const double vol = static_cast<double>(voxelize_parity(sphere, g, 0, 0, nullptr).count()) * g.voxel_volume();
    EXPECT_NEAR(vol / exact, 1.0, 4e-3) << "level " << level;
  }
}

TEST(ParityVoxelizer, NestedShellsAlternateInsideAndOutside) {
  // Parity counts crossings, so a shell inside a shell (same orientation)
  // bounds a cavity: filled between the shells, empty inside the inner one.
  // (The winding test keeps nested and overlapping shells filled.)
  const Mesh nested = test::concat({make_icosphere({0, 0, 0}, 1.0, 3), make_icosphere({0, 0, 0}, 0.5, 3)});
  const Grid g = resolve_grid({GridRequest::Kind::resolution, 40, 0, 1, {}, {}}, bounds(nested));
  const BitVolume v = voxelize_parity(nested, g, 0, 0, nullptr);
  for (std::int64_t k = 0; k < g.dims.z; ++k)
    for (std::int64_t j = 0; j < g.dims.y; ++j)
      for (std::int64_t i = 0; i < g.dims.x; ++i) {
        const double r = glm::length(g.center(i, j, k));
        if (r < 0.45 || r > 1.0) {
          ASSERT_FALSE(v.get(i, j, k)) << r;
        } else if (r > 0.52 && r < 0.94) {
          ASSERT_TRUE(v.get(i, j, k)) << r;
        }
      }
}

TEST(ParityVoxelizer, OverlappingClosedCubesCancelInTheOverlap) {
  // Two overlapping closed shells: parity sees two crossings around the
  // overlap and leaves it empty; this is why `winding` exists.
  const Mesh two = test::concat({make_box({0.25, 0.25, 0.25}, {6.25, 6.25, 6.25}), make_box({3.25, 3.25, 3.25}, {9.25, 9.25, 9.25})});
  const Grid g = cube_grid({0, 0, 0}, 1.0, 10);
  const BitVolume v = voxelize_parity(two, g, 0, 0, nullptr);
  EXPECT_FALSE(v.get(4, 4, 4));  // overlap
  EXPECT_TRUE(v.get(1, 1, 1));
  EXPECT_TRUE(v.get(8, 8, 8));
  EXPECT_EQ(v.count(), 2u * 216u - 2u * 27u);
}

TEST(VoteVoxelizer, CubeWithOneFaceRemovedIsRecovered) {
  // Without its +z face, parity along z streaks out of the top; along x and
  // y every column still crosses two walls, and they outvote it.
  const Mesh open = test::remove_face(make_box({1.25, 1.25, 1.25}, {7.75, 7.75, 7.75}), 2, 7.75);
  ASSERT_EQ(open.triangles.size(), 10u);
  const Grid g = cube_grid({0, 0, 0}, 1.0, 10);
  const BitVolume vote = voxelize_vote(open, g, 0, nullptr);
  EXPECT_EQ(vote.count(), 7u * 7u * 7u);  // centres 1.5 .. 7.5 on each axis
  for (std::int64_t k = 0; k < 10; ++k)
    for (std::int64_t j = 0; j < 10; ++j)
      for (std::int64_t i = 0; i < 10; ++i)
        ASSERT_EQ(vote.get(i, j, k), i >= 1 && i <= 7 && j >= 1 && j <= 7 && k >= 1 && k <= 7);
}

TEST(Grid, ResolutionFitsTheLongestAxisAndCentresTheMesh) {
  const Aabb b{{0, 0, 0}, {10, 5, 2.5}};
  const Grid g = resolve_grid({GridRequest::Kind::resolution, 20, 0, 2, {}, {}}, b);
  EXPECT_DOUBLE_EQ(g.voxel_size, 0.5);
  EXPECT_EQ(g.dims, glm::i64vec3(24, 14, 9));
  // Padding of 2 voxels on each side; the mesh is centred in its voxels.
  EXPECT_DOUBLE_EQ(g.origin.x, -1.0);
  EXPECT_DOUBLE_EQ(g.origin.y, -1.0);
  EXPECT_DOUBLE_EQ(g.origin.z, 1.25 - 0.5 * 5 * 0.5 - 1.0);
  // 10 / 0.1 must give 100 voxels, not 101 from rounding.
  const Grid h = resolve_grid({GridRequest::Kind::voxel_size, 0, 0.1, 0, {}, {}}, Aabb{{0, 0, 0}, {10, 1, 0}});
  EXPECT_EQ(h.dims, glm::i64vec3(100, 10, 1));
}

TEST(Grid, RejectsImpossibleRequestsWithActionableMessages) {
  const Aabb b{{0, 0, 0}, {1, 1, 1}};
  auto message = [&](GridRequest r) -> std::string {
    try {
      resolve_grid(r, b);
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::invalid_argument);
      return e.what();
    }
    return "";
  };
  EXPECT_NE(message({GridRequest::Kind::resolution, 0, 0, 0, {}, {}}).find("resolution must be"), std::string::npos);
  EXPECT_NE(message({GridRequest::Kind::voxel_size, 0, -1, 0, {}, {}}).find("voxel_size must be"), std::string::npos);
  EXPECT_NE(message({GridRequest::Kind::voxel_size, 0, 1e-6, 0, {}, {}}).find("use a larger voxel_size"), std::string::npos);
  EXPECT_NE(message({GridRequest::Kind::explicit_grid, 0, 1, 0, {}, {0, 1, 1}}).find("dims along x"), std::string::npos);
  try {
    resolve_grid({GridRequest::Kind::resolution, 10, 0, 0, {}, {}}, Aabb{{1, 1, 1}, {1, 1, 1}});
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("zero extent"), std::string::npos);
  }
}

TEST(VoteVoxelizer, EqualsParityOnClosedMeshesAndRepairsACrack) {
  const Mesh sphere = make_icosphere({0.01, 0.02, 0.03}, 1.0, 4);
  const Grid g = resolve_grid({GridRequest::Kind::resolution, 48, 0, 1, {}, {}}, bounds(sphere));
  const BitVolume parity = voxelize_parity(sphere, g, 0, 0, nullptr);
  const BitVolume vote = voxelize_vote(sphere, g, 0, nullptr);
  EXPECT_TRUE(std::equal(parity.data(), parity.data() + parity.word_count(), vote.data()));

  // Remove one small triangle: parity along x streaks through that column;
  // the vote along y and z outvotes the streak.
  Mesh cracked = sphere;
  std::size_t victim = 0;
  double best = -1;
  for (std::size_t t = 0; t < cracked.triangles.size(); ++t) {
    const glm::dvec3 c = (glm::dvec3(cracked.corner(t, 0)) + glm::dvec3(cracked.corner(t, 1)) + glm::dvec3(cracked.corner(t, 2))) / 3.0;
    if (c.x > best) {
      best = c.x;
      victim = t;
    }
  }
  cracked.triangles.erase(cracked.triangles.begin() + static_cast<std::ptrdiff_t>(victim));
  const BitVolume cracked_vote = voxelize_vote(cracked, g, 0, nullptr);
  std::uint64_t diff = 0;
  for (std::size_t w = 0; w < parity.word_count(); ++w) diff += std::popcount(parity.data()[w] ^ cracked_vote.data()[w]);
  EXPECT_LE(diff, 2u);
}

TEST(Voxelize, SolidPlusSurfaceIsTheUnionAndKeepsThinWalls) {
  // A closed box with a wall thinner than a voxel welded onto it.
  const Mesh part = test::concat({make_box({1.25, 1.25, 1.25}, {5.75, 5.75, 5.75}), make_box({5.75, 2.1, 2.1}, {9.2, 2.3, 5.2})});
  const Grid g = cube_grid({0, 0, 0}, 1.0, 11);
  VoxelizeOptions options;
  options.mode = VoxelMode::solid_and_surface;
  const BitVolume both = voxelize(part, g, options);
  const BitVolume solid = voxelize_parity(part, g, 0, 0, nullptr);
  const BitVolume surface = voxelize_surface(part, g, 0, nullptr);
  std::uint64_t expected = 0;
  for (std::size_t w = 0; w < both.word_count(); ++w) {
    ASSERT_EQ(both.data()[w], solid.data()[w] | surface.data()[w]);
    expected += std::popcount(solid.data()[w] | surface.data()[w]);
  }
  EXPECT_EQ(both.count(), expected);
  // The fin (y in [2.1, 2.3]) holds no voxel centre but is kept.
  EXPECT_FALSE(solid.get(8, 2, 3));
  EXPECT_TRUE(both.get(8, 2, 3));
  options.mode = VoxelMode::surface;
  EXPECT_EQ(voxelize(part, g, options).count(), surface.count());
}

TEST(SurfaceVoxelizer, AxisAlignedBoxShellIsExact) {
  // Box [2.25, 9.75] in unit voxels: surface voxels are the cubes the faces
  // touch: index ranges 2..9 per axis, shell only.
  const Mesh box = make_box({2.25, 2.25, 2.25}, {9.75, 9.75, 9.75});
  const Grid g = cube_grid({0, 0, 0}, 1.0, 12);
  const BitVolume s = voxelize_surface(box, g, 0, nullptr);
  std::uint64_t expected = 0;
  for (std::int64_t k = 0; k < 12; ++k)
    for (std::int64_t j = 0; j < 12; ++j)
      for (std::int64_t i = 0; i < 12; ++i) {
        const bool in = i >= 2 && i <= 9 && j >= 2 && j <= 9 && k >= 2 && k <= 9;
        const bool shell = in && (i == 2 || i == 9 || j == 2 || j == 9 || k == 2 || k == 9);
        expected += shell;
        ASSERT_EQ(s.get(i, j, k), shell) << i << ',' << j << ',' << k;
      }
  EXPECT_EQ(s.count(), expected);
}

TEST(SurfaceVoxelizer, EveryTriangleSampleLiesInAMarkedVoxelAndMarkedVoxelsAreNearTheSurface) {
  const Mesh torus = make_torus({0.01, 0.02, 0.03}, 2.0, 0.5, 40, 20);
  const Grid g = resolve_grid({GridRequest::Kind::resolution, 50, 0, 1, {}, {}}, bounds(torus));
  const BitVolume s = voxelize_surface(torus, g, 0, nullptr);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  for (std::size_t t = 0; t < torus.triangles.size(); ++t) {
    for (int n = 0; n < 20; ++n) {
      double a = uni(rng), b = uni(rng);
      if (a + b > 1) a = 1 - a, b = 1 - b;
      const glm::dvec3 p = glm::dvec3(torus.corner(t, 0)) + a * (glm::dvec3(torus.corner(t, 1)) - glm::dvec3(torus.corner(t, 0))) +
                           b * (glm::dvec3(torus.corner(t, 2)) - glm::dvec3(torus.corner(t, 0)));
      const glm::i64vec3 idx(glm::floor((p - g.origin) / g.voxel_size));
      ASSERT_TRUE(s.get(idx.x, idx.y, idx.z)) << "triangle " << t;
    }
  }
  // Conservative but tight: a marked voxel's centre is within half a diagonal
  // of the torus surface.
  for (std::int64_t k = 0; k < g.dims.z; ++k)
    for (std::int64_t j = 0; j < g.dims.y; ++j)
      for (std::int64_t i = 0; i < g.dims.x; ++i) {
        if (!s.get(i, j, k)) continue;
        const glm::dvec3 p = g.center(i, j, k) - glm::dvec3(0.01, 0.02, 0.03);
        const double ring = std::sqrt(p.x * p.x + p.y * p.y) - 2.0;
        const double dist = std::abs(std::sqrt(ring * ring + p.z * p.z) - 0.5);
        ASSERT_LE(dist, 0.5 * std::sqrt(3.0) * g.voxel_size + 0.02) << i << ',' << j << ',' << k;
      }
}

TEST(SurfaceVoxelizer, ThinWallMissedBySolidIsKeptBySurface) {
  // A plate 0.3 voxel thick between centre planes: no centre is inside it.
  const Mesh plate = make_box({1.1, 1.1, 4.6}, {8.9, 8.9, 4.9});
  const Grid g = cube_grid({0, 0, 0}, 1.0, 10);
  EXPECT_EQ(voxelize_parity(plate, g, 0, 0, nullptr).count(), 0u);
  const BitVolume s = voxelize_surface(plate, g, 0, nullptr);
  EXPECT_EQ(s.count(), 8u * 8u);
  for (std::int64_t j = 1; j <= 8; ++j)
    for (std::int64_t i = 1; i <= 8; ++i) EXPECT_TRUE(s.get(i, j, 4));
}

}  // namespace
}  // namespace voxd
