// Orientation repair against meshes whose right orientation is known: the
// check is the mesh report's independent edge count (no inconsistent edge
// left) and the signed volume by the divergence theorem against the closed
// form, never the repair's own counts alone.
#include <cmath>

#include <gtest/gtest.h>

#include "support/test_meshes.h"
#include "voxd/mesh_orientation.h"
#include "voxd/mesh_report.h"

namespace voxd {
namespace {

using test::concat;
using test::flipped;
using test::make_box;

// Turns every `stride`-th triangle.
Mesh with_flipped_triangles(Mesh mesh, std::size_t stride) {
  for (std::size_t t = 0; t < mesh.triangles.size(); t += stride) std::swap(mesh.triangles[t][1], mesh.triangles[t][2]);
  return mesh;
}

double signed_volume(const Mesh& mesh) { return make_mesh_report(mesh).volume; }

TEST(OrientOutward, LeavesAnOutwardClosedMeshAsItIs) {
  Mesh box = make_box({0, 0, 0}, {2, 3, 4});
  const Mesh before = box;
  const OrientationRepair r = orient_outward(box);
  EXPECT_FALSE(r.changed());
  EXPECT_EQ(r.components, 1u);
  EXPECT_TRUE(r.closed());
  EXPECT_EQ(box.triangles, before.triangles);
}

TEST(OrientOutward, TurnsAnInsideOutMeshRoundWhole) {
  Mesh box = flipped(make_box({0, 0, 0}, {2, 3, 4}));
  ASSERT_DOUBLE_EQ(signed_volume(box), -24.0);
  const OrientationRepair r = orient_outward(box);
  EXPECT_EQ(r.inverted_components, 1u);
  EXPECT_EQ(r.flipped_triangles, box.triangles.size());
  EXPECT_EQ(r.inconsistent_triangles, 0u);
  EXPECT_DOUBLE_EQ(signed_volume(box), 24.0);
}

TEST(OrientOutward, TurnsTrianglesThatDisagreeWithTheirNeighbours) {
  Mesh sphere = with_flipped_triangles(test::make_icosphere({1, 2, 3}, 5.0, 3), 7);
  const MeshReport before = make_mesh_report(sphere);
  ASSERT_GT(before.inconsistent_edges, 0u);
  const double expected = signed_volume(test::make_icosphere({1, 2, 3}, 5.0, 3));
  const OrientationRepair r = orient_outward(sphere);
  EXPECT_EQ(r.inconsistent_edges, before.inconsistent_edges);
  const MeshReport after = make_mesh_report(sphere);
  EXPECT_EQ(after.inconsistent_edges, 0u);
  EXPECT_TRUE(after.watertight);
  EXPECT_NEAR(after.volume, expected, 1e-9 * expected);
  EXPECT_EQ(r.inverted_components, 0u);
  EXPECT_EQ(r.flipped_triangles, (sphere.triangles.size() + 6) / 7);
  EXPECT_EQ(r.inconsistent_triangles, r.flipped_triangles);
}

TEST(OrientOutward, ASphereMostlyInsideOutComesOutOutward) {
  // Six of every seven triangles inside out: the walk keeps the majority
  // (inward), the sign turns the whole sphere.
  Mesh sphere = flipped(with_flipped_triangles(test::make_icosphere({0, 0, 0}, 2.0, 2), 7));
  orient_outward(sphere);
  const MeshReport after = make_mesh_report(sphere);
  EXPECT_EQ(after.inconsistent_edges, 0u);
  EXPECT_GT(after.volume, 0.0);
}

TEST(OrientOutward, KeepsACavityACavity) {
  // A hollow cube: the inner shell faces inward, as a void's surface must.
  Mesh hollow = concat({make_box({0, 0, 0}, {10, 10, 10}), flipped(make_box({2, 2, 2}, {8, 8, 8}))});
  const Mesh before = hollow;
  const OrientationRepair r = orient_outward(hollow);
  EXPECT_EQ(r.components, 2u);
  EXPECT_FALSE(r.changed());
  EXPECT_EQ(hollow.triangles, before.triangles);
}

TEST(OrientOutward, TurnsAHollowPartWrittenInsideOutBothShells) {
  Mesh hollow = flipped(concat({make_box({0, 0, 0}, {10, 10, 10}), flipped(make_box({2, 2, 2}, {8, 8, 8}))}));
  ASSERT_DOUBLE_EQ(signed_volume(hollow), -(1000.0 - 216.0));
  const OrientationRepair r = orient_outward(hollow);
  EXPECT_EQ(r.inverted_components, 2u);
  EXPECT_DOUBLE_EQ(signed_volume(hollow), 1000.0 - 216.0);
}

TEST(OrientOutward, AnOpenHollowPartWrittenInsideOutKeepsItsCavity) {
  // Each face of the outer shell in turn missing a triangle: whichever way
  // a ray from the cavity leaves, most rays still cross the shell.
  for (std::size_t missing = 0; missing < 12; ++missing) {
    Mesh outer = flipped(make_box({0, 0, 0}, {10, 10, 10}));
    outer.triangles.erase(outer.triangles.begin() + static_cast<std::ptrdiff_t>(missing));
    Mesh hollow = concat({outer, make_box({2, 2, 2}, {8, 8, 8})});  // the cavity's shell inside out too
    const OrientationRepair r = orient_outward(hollow);
    EXPECT_EQ(r.inverted_components, 2u) << missing;
    // The cavity's shell faces inward again: its own signed volume is -216.
    Mesh cavity;
    cavity.vertices = hollow.vertices;
    cavity.triangles.assign(hollow.triangles.end() - 12, hollow.triangles.end());
    EXPECT_DOUBLE_EQ(signed_volume(cavity), -216.0) << missing;
  }
}

TEST(OrientOutward, ASolidInACavityStaysSolid) {
  Mesh nested = concat({make_box({0, 0, 0}, {10, 10, 10}), flipped(make_box({2, 2, 2}, {8, 8, 8})),
                        make_box({4, 4, 4}, {6, 6, 6})});
  EXPECT_FALSE(orient_outward(nested).changed());
  Mesh inverted = flipped(nested);
  EXPECT_EQ(orient_outward(inverted).inverted_components, 3u);
  EXPECT_DOUBLE_EQ(signed_volume(inverted), 1000.0 - 216.0 + 8.0);
}

TEST(OrientOutward, TurnsOnlyThePartOfAnAssemblyThatIsInsideOut) {
  Mesh assembly = concat({make_box({0, 0, 0}, {1, 1, 1}), flipped(make_box({3, 0, 0}, {5, 2, 2}))});
  const OrientationRepair r = orient_outward(assembly);
  EXPECT_EQ(r.components, 2u);
  EXPECT_EQ(r.inverted_components, 1u);
  EXPECT_EQ(r.flipped_triangles, 12u);
  EXPECT_DOUBLE_EQ(signed_volume(assembly), 1.0 + 8.0);
}

TEST(OrientOutward, TurnsAnOpenHullWrittenInsideOut) {
  // A box with its top missing encloses a clear side, open or not.
  Mesh open = flipped(test::remove_face(make_box({0, 0, 0}, {10, 10, 10}), 2, 10.0));
  const OrientationRepair r = orient_outward(open);
  EXPECT_FALSE(r.closed());
  EXPECT_EQ(r.boundary_edges, 4u);
  EXPECT_EQ(r.inverted_components, 1u);
  EXPECT_EQ(r.flipped_triangles, open.triangles.size());
  // Outward now: the bottom's normal points down.
  const auto& t = open.triangles[0];
  Mesh outward = test::remove_face(make_box({0, 0, 0}, {10, 10, 10}), 2, 10.0);
  EXPECT_EQ(t, outward.triangles[0]);
}

TEST(OrientOutward, LeavesAFlatSheetAsItIs) {
  Mesh sheet = test::remove_face(make_box({0, 0, 0}, {4, 4, 1}), 2, 0.0);
  // Only the top face of the box: remove everything but the z = 1 face.
  std::erase_if(sheet.triangles, [&](const auto& t) {
    for (auto v : t)
      if (sheet.vertices[v].z != 1.0f) return true;
    return false;
  });
  ASSERT_EQ(sheet.triangles.size(), 2u);
  Mesh down = flipped(sheet);
  const Mesh before = down;
  const OrientationRepair r = orient_outward(down);
  EXPECT_EQ(r.components, 1u);
  EXPECT_EQ(r.boundary_edges, 4u);
  EXPECT_FALSE(r.changed());
  EXPECT_EQ(down.triangles, before.triangles);
}

TEST(OrientOutward, CountsTheEdgesNoOrientationCanMend) {
  // A Moebius strip of eight quads: one half twist, so the last quad joins the
  // first the wrong way round whatever the walk does.
  Mesh strip;
  const int quads = 8;
  for (int i = 0; i < quads; ++i) {
    const double a = 2.0 * 3.14159265358979 * i / quads, half = a / 2.0;
    const glm::dvec3 centre(3.0 * std::cos(a), 3.0 * std::sin(a), 0.0);
    const glm::dvec3 across(std::cos(half) * std::cos(a), std::cos(half) * std::sin(a), std::sin(half));
    strip.vertices.push_back(glm::vec3(centre - across));
    strip.vertices.push_back(glm::vec3(centre + across));
  }
  for (std::uint32_t i = 0; i < quads; ++i) {
    const std::uint32_t a = 2 * i, b = 2 * i + 1;
    // The last quad joins the first with its sides swapped: the half twist.
    const std::uint32_t c = i + 1 < quads ? 2 * (i + 1) : 1, d = i + 1 < quads ? 2 * (i + 1) + 1 : 0;
    strip.triangles.push_back({a, c, b});
    strip.triangles.push_back({b, c, d});
  }
  const OrientationRepair r = orient_outward(strip);
  EXPECT_EQ(r.components, 1u);
  EXPECT_EQ(r.unorientable_edges, 1u);
  EXPECT_FALSE(r.closed());
}

TEST(OrientOutward, LeavesAnEmptyMeshAlone) {
  Mesh empty;
  const OrientationRepair r = orient_outward(empty);
  EXPECT_EQ(r.components, 0u);
  EXPECT_FALSE(r.changed());
}

}  // namespace
}  // namespace voxd
