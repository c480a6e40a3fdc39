// Mass properties against analytic values: boxes (inertia m(b²+c²)/12), the
// parallel-axis theorem under translation, rotation of the tensor, and the
// voxel model of a box that fills whole voxels exactly.
#include <gtest/gtest.h>

#include "support/test_meshes.h"
#include "voxd/analysis/mass_properties.h"
#include "voxd/transform.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd {
namespace {

void expect_box(const MassProperties& p, glm::dvec3 lo, glm::dvec3 hi, double tol) {
  const glm::dvec3 e = hi - lo;
  const double v = e.x * e.y * e.z;
  EXPECT_NEAR(p.volume, v, tol * v);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(p.centroid[i], (lo[i] + hi[i]) / 2, tol * glm::length(e));
  const double ixx = v * (e.y * e.y + e.z * e.z) / 12, iyy = v * (e.x * e.x + e.z * e.z) / 12,
               izz = v * (e.x * e.x + e.y * e.y) / 12;
  EXPECT_NEAR(p.inertia[0][0], ixx, tol * ixx);
  EXPECT_NEAR(p.inertia[1][1], iyy, tol * iyy);
  EXPECT_NEAR(p.inertia[2][2], izz, tol * izz);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (i != j) {
        EXPECT_NEAR(p.inertia[i][j], 0.0, tol * izz) << i << j;
      }
}

TEST(MeshMassProperties, BoxIsExactWhereverItIs) {
  expect_box(mesh_mass_properties(test::make_box({0, 0, 0}, {2, 3, 5})), {0, 0, 0}, {2, 3, 5}, 1e-12);
  // Far from the origin: moments are taken about the part, not the origin.
  expect_box(mesh_mass_properties(test::make_box({1000, -2000, 3000}, {1002, -1997, 3005})), {1000, -2000, 3000},
             {1002, -1997, 3005}, 1e-9);
}

TEST(MeshMassProperties, RotatedBoxHasTheRotatedTensor) {
  Mesh m = test::make_box({-1, -2, -3}, {1, 2, 3});
  const glm::dmat3 r = rotation_from_axis_angle({1.0, 2.0, 0.5}, 33.0);
  rotate_mesh(m, r);
  const MassProperties p = mesh_mass_properties(m);
  const double v = 2 * 4 * 6;
  const glm::dmat3 body(v * (16 + 36) / 12, 0, 0, 0, v * (4 + 36) / 12, 0, 0, 0, v * (4 + 16) / 12);
  const glm::dmat3 expected = r * body * glm::transpose(r);
  EXPECT_NEAR(p.volume, v, 1e-4);  // float vertices after rotation
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(p.inertia[i][j], expected[i][j], 1e-3) << i << j;
}

TEST(MeshMassProperties, HollowBoxSubtractsItsCavityAndInsideOutIsNegative) {
  const Mesh hollow = test::concat({test::make_box({0, 0, 0}, {4, 4, 4}), test::flipped(test::make_box({1, 1, 1}, {3, 3, 3}))});
  const MassProperties p = mesh_mass_properties(hollow);
  EXPECT_NEAR(p.volume, 64 - 8, 1e-12);
  const double outer = 64 * (16 + 16) / 12.0, inner = 8 * (4 + 4) / 12.0;
  EXPECT_NEAR(p.inertia[0][0], outer - inner, 1e-9);
  EXPECT_NEAR(mesh_mass_properties(test::flipped(test::make_box({0, 0, 0}, {1, 2, 3}))).volume, -6.0, 1e-12);
}

TEST(MeshMassProperties, SphereApproachesTheAnalyticInertia) {
  const Mesh s = test::make_icosphere({0.5, -1, 2}, 2.0, 5);
  const MassProperties p = mesh_mass_properties(s);
  EXPECT_NEAR(p.volume, test::mesh_volume(s), 1e-9);
  const double i = 0.4 * p.volume * 4.0;  // 2/5 m r², r = 2
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(p.inertia[a][a], i, 0.01 * i);
  EXPECT_NEAR(glm::length(p.centroid - glm::dvec3(0.5, -1, 2)), 0.0, 1e-9);
}

TEST(VoxelMassProperties, BoxOnVoxelBoundariesIsExact) {
  // Box [2, 7] x [1, 4] x [3, 11] on a unit grid: exactly the voxels inside.
  Grid g;
  g.origin = {0, 0, 0};
  g.voxel_size = 0.5;
  g.dims = {20, 12, 30};
  const glm::dvec3 lo{1.0, 0.5, 1.5}, hi{3.5, 2.0, 5.5};
  const BitVolume v = voxelize(test::make_box(lo, hi), g, {});
  const MassProperties p = voxel_mass_properties(v);
  expect_box(p, lo, hi, 1e-12);
  EXPECT_EQ(p.bbox.min, lo);
  EXPECT_EQ(p.bbox.max, hi);
  // Thread count does not change the sums beyond rounding.
  const MassProperties one = voxel_mass_properties(v, 1);
  EXPECT_NEAR(one.inertia[1][1], p.inertia[1][1], 1e-12 * p.inertia[1][1]);
}

TEST(VoxelMassProperties, VoxelModelOfASphereConvergesToTheMesh) {
  const Mesh s = test::make_icosphere({0.3, 0.1, -0.2}, 1.0, 5);
  const MassProperties exact = mesh_mass_properties(s);
  double previous_error = 1e9;
  for (int n : {32, 64, 128}) {
    Grid g;
    g.voxel_size = 2.4 / n;
    g.origin = glm::dvec3(0.3, 0.1, -0.2) - 1.2;
    g.dims = {n, n, n};
    const MassProperties p = voxel_mass_properties(voxelize(s, g, {}));
    const double error = std::abs(p.inertia[2][2] - exact.inertia[2][2]) / exact.inertia[2][2];
    EXPECT_LT(error, 3.0 / n) << n;
    EXPECT_LT(std::abs(p.volume - exact.volume) / exact.volume, 2.0 / n) << n;
    EXPECT_LT(glm::length(p.centroid - exact.centroid), g.voxel_size) << n;
    EXPECT_LT(error, previous_error * 1.01) << n;
    previous_error = error;
  }
}

TEST(VoxelMassProperties, EmptyVolumeHasZeroVolume) {
  Grid g;
  g.dims = {5, 5, 5};
  const MassProperties p = voxel_mass_properties(BitVolume(g));
  EXPECT_EQ(p.volume, 0.0);
}

}  // namespace
}  // namespace voxd
