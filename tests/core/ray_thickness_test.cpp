// The reference the wall-thickness tests measure against (support/
// ray_thickness.h), checked itself on shapes whose ray thickness is known
// in closed form.
#include <gtest/gtest.h>

#include <cmath>

#include "support/ray_thickness.h"
#include "support/test_meshes.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd {
namespace {

TEST(RayThickness, APlatesFacesReadItsThicknessAndItsSidesItsWidths) {
  const Mesh plate = test::make_box({0, 0, 0}, {10, 8, 1.5});
  int faces = 0;
  for (const test::SurfacePoint& p : test::sample_surface(plate, 500, 7)) {
    const auto t = test::ray_thickness(plate, p);
    ASSERT_TRUE(t);
    const double want = std::abs(p.normal.z) > 0.5 ? 1.5 : std::abs(p.normal.y) > 0.5 ? 8.0 : 10.0;
    EXPECT_NEAR(*t, want, 1e-6) << p.point.x << " " << p.point.y << " " << p.point.z;
    faces += std::abs(p.normal.z) > 0.5;
  }
  // Sampled by area: the two faces are 160 of the 214 square units.
  EXPECT_NEAR(faces / 500.0, 160.0 / 214.0, 0.05);
}

TEST(RayThickness, ATubesAndAShellsWallsReadRMinusRWithinTheirFacets) {
  // Facets of a tube of N segments lie within R (1 - cos(2 pi / N)) of the
  // cylinder: so does the ray across the wall.
  const double R = 6, r = 4.5;
  const int n = 192;
  const Mesh tube = test::make_tube(R, r, 0, 6, n);
  const double facets = R * (1 - std::cos(2 * M_PI / n));
  std::size_t walls = 0;
  for (const test::SurfacePoint& p : test::sample_surface(tube, 400, 3)) {
    if (std::abs(p.normal.z) > 0.5) continue;  // the annular caps
    const auto t = test::ray_thickness(tube, p);
    ASSERT_TRUE(t);
    EXPECT_NEAR(*t, R - r, facets + 1e-6);
    ++walls;
  }
  EXPECT_GT(walls, 300u);
  const Mesh shell = test::concat({test::make_icosphere({0, 0, 0}, 6, 4), test::flipped(test::make_icosphere({0, 0, 0}, 4.8, 4))});
  for (const test::SurfacePoint& p : test::sample_surface(shell, 200, 5)) {
    const auto t = test::ray_thickness(shell, p);
    ASSERT_TRUE(t);
    EXPECT_NEAR(*t, 1.2, 0.03);
  }
}

TEST(RayThickness, AnOpenMeshHasNoThicknessWhereItsRaysLeave) {
  const Mesh open = test::remove_face(test::make_box({0, 0, 0}, {4, 4, 1}), 2, 1.0);
  int bottom = 0;
  for (const test::SurfacePoint& p : test::sample_surface(open, 200, 9)) {
    if (p.normal.z > -0.5) continue;
    EXPECT_FALSE(test::ray_thickness(open, p)) << p.point.x << " " << p.point.y;
    ++bottom;
  }
  EXPECT_GT(bottom, 50);
}

TEST(RayThickness, SharpEdgesAreTheBoxsTwelveAndATubesFourRims) {
  EXPECT_EQ(test::sharp_edges(test::make_box({0, 0, 0}, {3, 2, 1}), 30).size(), 12u);
  // Facets 360/64 = 5.6 degrees apart are smooth; the rims of its two caps are not.
  EXPECT_EQ(test::sharp_edges(test::make_tube(3, 2, 0, 4, 64), 30).size(), 4u * 64u);
  const auto edges = test::sharp_edges(test::make_box({0, 0, 0}, {3, 2, 1}), 30);
  EXPECT_NEAR(test::distance_to_edges({1.5, 0.0, 0.5}, edges), 0.5, 1e-9);  // the middle of a side
  EXPECT_NEAR(test::distance_to_edges({1.5, -1.0, 0.0}, edges), 1.0, 1e-9);
}

TEST(RayThickness, AMapReadingTheWallEverywhereAgreesAndOneVoxelOffIsOffByOne) {
  const Mesh plate = test::make_box({0, 0, 0}, {6, 5, 1});
  GridRequest request;
  request.kind = GridRequest::Kind::voxel_size;
  request.voxel_size = 0.1;
  request.padding = 2;
  const BitVolume solid = voxelize_parity(plate, resolve_grid(request, bounds(plate)), 0, 0, nullptr);
  // 6 voxels from the edges only the two big faces remain (no point of a
  // 1 mm side is more than 0.5 mm from an edge): 1 mm = 10 voxels.
  DenseVolume<float> map(solid.grid(), 10.0f);
  const test::WallAgreement exact = test::compare_with_rays(plate, solid, map, 300, 6.0);
  EXPECT_EQ(exact.points, 300u);
  EXPECT_EQ(exact.within_1, 1.0);
  EXPECT_NEAR(exact.p01, 0.0, 1e-4);
  EXPECT_NEAR(exact.p99, 0.0, 1e-4);
  EXPECT_NEAR(exact.min, 1.0, 1e-6);
  EXPECT_NEAR(exact.ray_mean, 1.0, 1e-6);
  DenseVolume<float> low(solid.grid(), 8.5f);
  const test::WallAgreement off = test::compare_with_rays(plate, solid, low, 300, 6.0);
  EXPECT_EQ(off.within_1, 0.0);
  EXPECT_EQ(off.within_1_5, 1.0);
  EXPECT_NEAR(off.p50, -1.5, 1e-4);
}

}  // namespace
}  // namespace voxd
