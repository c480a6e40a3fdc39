// Welding and the mesh report: counts, topology and geometry against meshes
// whose answers are known, CAD-like parts made in code and a real open mesh.
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "support/assimp_models.h"
#include "support/test_meshes.h"
#include "support/test_parts.h"
#include "voxd/mesh_io/mesh_decode.h"
#include "voxd/mesh_report.h"

namespace voxd {
namespace {

using test::soup_of;

void expect_same_report(const MeshReport& a, const MeshReport& b) {
  EXPECT_EQ(a.triangles, b.triangles);
  EXPECT_EQ(a.vertices, b.vertices);
  EXPECT_EQ(a.bbox.min, b.bbox.min);
  EXPECT_EQ(a.bbox.max, b.bbox.max);
  EXPECT_EQ(a.degenerate_triangles, b.degenerate_triangles);
  EXPECT_EQ(a.boundary_edges, b.boundary_edges);
  EXPECT_EQ(a.nonmanifold_edges, b.nonmanifold_edges);
  EXPECT_EQ(a.inconsistent_edges, b.inconsistent_edges);
  EXPECT_EQ(a.watertight, b.watertight);
  EXPECT_DOUBLE_EQ(a.surface_area, b.surface_area);
  EXPECT_DOUBLE_EQ(a.volume, b.volume);
}

const Mesh& unit_box() {
  static const Mesh m = test::make_box({1, 2, 3}, {2, 4, 6});  // 1 x 2 x 3
  return m;
}

TEST(WeldVertices, MergesIdenticalPositionsKeepingTriangleOrder) {
  const Mesh welded = weld_vertices(soup_of(unit_box()));
  EXPECT_EQ(welded.vertices.size(), 8u);
  ASSERT_EQ(welded.triangles.size(), 12u);
  for (std::size_t t = 0; t < 12; ++t)
    for (int c = 0; c < 3; ++c) EXPECT_EQ(welded.corner(t, c), unit_box().corner(t, c));
}

TEST(WeldVertices, NegativeZeroIsZero) {
  Mesh m;
  m.vertices = {{0.0f, 1, 0}, {-0.0f, 1, 0}, {1, -0.0f, 0}, {1, 0.0f, 0}, {0, 0, 1}};
  m.triangles = {{0, 2, 4}, {1, 3, 4}};
  const Mesh welded = weld_vertices(m);
  EXPECT_EQ(welded.vertices.size(), 3u);
  EXPECT_EQ(welded.triangles[0], welded.triangles[1]);
}

TEST(WeldVertices, KeepsDistinctPositionsApart) {
  // Neighbouring floats must not merge: welding is exact, not by tolerance.
  Mesh m;
  m.vertices = {{1, 1, 1}, {std::nextafter(1.0f, 2.0f), 1, 1}, {1, 1, std::nextafter(1.0f, 0.0f)}};
  m.triangles = {{0, 1, 2}};
  EXPECT_EQ(weld_vertices(m).vertices.size(), 3u);
  // A large indexed mesh with no duplicates stays as it is.
  const Mesh sphere = test::make_icosphere({0, 0, 0}, 1, 5);
  const Mesh welded = weld_vertices(sphere);
  EXPECT_EQ(welded.vertices, sphere.vertices);
  EXPECT_EQ(welded.triangles, sphere.triangles);
}

TEST(MeshReport, Box) {
  const MeshReport r = make_mesh_report(unit_box());
  EXPECT_EQ(r.triangles, 12u);
  EXPECT_EQ(r.vertices, 8u);
  EXPECT_EQ(r.bbox.min, glm::dvec3(1, 2, 3));
  EXPECT_EQ(r.bbox.max, glm::dvec3(2, 4, 6));
  EXPECT_EQ(r.degenerate_triangles, 0u);
  EXPECT_EQ(r.boundary_edges, 0u);
  EXPECT_EQ(r.nonmanifold_edges, 0u);
  EXPECT_EQ(r.inconsistent_edges, 0u);
  EXPECT_TRUE(r.watertight);
  EXPECT_EQ(r.surface_area, 2.0 * (1 * 2 + 2 * 3 + 1 * 3));
  EXPECT_EQ(r.volume, 6.0);
}

TEST(MeshReport, InsideOutBoxHasNegativeVolume) {
  const MeshReport r = make_mesh_report(test::flipped(unit_box()));
  EXPECT_TRUE(r.watertight);
  EXPECT_EQ(r.inconsistent_edges, 0u);  // flipped consistently
  EXPECT_EQ(r.volume, -6.0);
}

TEST(MeshReport, SoupAndIndexedTwinsGiveTheSameReport) {
  for (const Mesh& mesh : {unit_box(), test::make_icosphere({1, -2, 0.5}, 3, 3), test::make_torus({0, 0, 0}, 4, 1, 40, 16)}) {
    const MeshReport indexed = make_mesh_report(mesh);
    expect_same_report(make_mesh_report(soup_of(mesh)), indexed);
    // And through the binary STL decoder, the usual way soups arrive.
    expect_same_report(make_mesh_report(decode_mesh(test::to_binary_stl(mesh))), indexed);
    EXPECT_TRUE(indexed.watertight);
    EXPECT_EQ(indexed.vertices, mesh.vertices.size());
  }
}

TEST(MeshReport, IcosphereAndTorusGeometry) {
  const Mesh sphere = test::make_icosphere({0, 0, 0}, 2, 4);
  const MeshReport s = make_mesh_report(sphere);
  EXPECT_NEAR(s.volume, test::mesh_volume(sphere), 1e-12 * s.volume);
  EXPECT_NEAR(s.volume, 4.0 / 3.0 * M_PI * 8, 0.01 * s.volume);   // a polyhedron slightly inside the sphere
  EXPECT_NEAR(s.surface_area, 4.0 * M_PI * 4, 0.01 * s.surface_area);
  EXPECT_EQ(s.vertices, 2562u);  // 10 * 4^4 + 2, Euler for a sphere
  const Mesh torus = test::make_torus({5, 5, 5}, 3, 1, 64, 32);
  const MeshReport t = make_mesh_report(torus);
  EXPECT_TRUE(t.watertight);
  EXPECT_NEAR(t.volume, 2 * M_PI * M_PI * 3 * 1, 0.01 * t.volume);
  EXPECT_NEAR(t.volume, test::mesh_volume(torus), 1e-9 * t.volume);  // about another origin
}

TEST(MeshReport, BoxWithOneFaceRemovedHasFourBoundaryEdges) {
  const Mesh open_box = test::remove_face(unit_box(), 2, 6.0);  // the top
  ASSERT_EQ(open_box.triangles.size(), 10u);
  const MeshReport r = make_mesh_report(open_box);
  EXPECT_EQ(r.boundary_edges, 4u);
  EXPECT_EQ(r.nonmanifold_edges, 0u);
  EXPECT_EQ(r.inconsistent_edges, 0u);
  EXPECT_FALSE(r.watertight);
  EXPECT_EQ(r.vertices, 8u);
  EXPECT_EQ(r.surface_area, 22.0 - 2.0);
}

TEST(MeshReport, FlippedTriangleMakesInconsistentEdges) {
  Mesh m = unit_box();
  std::swap(m.triangles[5][1], m.triangles[5][2]);
  const MeshReport r = make_mesh_report(m);
  EXPECT_EQ(r.inconsistent_edges, 3u);  // each of its edges now runs the same way as its neighbour's
  EXPECT_EQ(r.boundary_edges, 0u);
  // Closed but not oriented: its volume is wrong, so it is not watertight.
  EXPECT_FALSE(r.watertight);
  EXPECT_NE(r.volume, 6.0);
}

TEST(MeshReport, ACollapsedTriangleOnAClosedBoxLeavesItWatertight) {
  Mesh m = unit_box();
  m.vertices.push_back({1, 2, 3});  // vertex 0's position again
  m.triangles.push_back({0, 8, 1});
  const MeshReport r = make_mesh_report(m);
  EXPECT_EQ(r.degenerate_triangles, 1u);
  EXPECT_EQ(r.boundary_edges + r.nonmanifold_edges + r.inconsistent_edges, 0u);
  EXPECT_TRUE(r.watertight);
  EXPECT_DOUBLE_EQ(r.volume, 6.0);
}

TEST(MeshReport, ThreeTrianglesOnOneEdgeAreNonManifold) {
  // A fin on the box's bottom edge from vertex 0 (1,2,3) to vertex 1 (2,2,3).
  Mesh m = unit_box();
  m.vertices.push_back({1.5f, 1.0f, 2.0f});
  m.triangles.push_back({0, 1, 8});
  const MeshReport r = make_mesh_report(m);
  EXPECT_EQ(r.nonmanifold_edges, 1u);
  EXPECT_EQ(r.boundary_edges, 2u);  // the fin's two free edges
  EXPECT_FALSE(r.watertight);
  EXPECT_EQ(r.vertices, 9u);
}

TEST(MeshReport, CountsDegenerateTriangles) {
  Mesh m = unit_box();
  // Collinear corners, distinct vertices.
  m.vertices.push_back({0, 0, 0});
  m.vertices.push_back({1, 1, 1});
  m.vertices.push_back({3, 3, 3});
  m.triangles.push_back({8, 9, 10});
  // Two corners at the same position (distinct indices, welded together).
  m.vertices.push_back({1, 2, 3});
  m.triangles.push_back({0, 11, 1});
  const MeshReport r = make_mesh_report(m);
  EXPECT_EQ(r.degenerate_triangles, 2u);
  EXPECT_EQ(r.triangles, 14u);
  EXPECT_EQ(r.surface_area, 22.0);  // neither adds area
  // The collinear sliver has three free edges; the collapsed one takes no
  // part in the topology.
  EXPECT_EQ(r.boundary_edges, 3u);
  EXPECT_EQ(r.nonmanifold_edges, 0u);
}

TEST(MeshReport, EmptyMesh) {
  const MeshReport r = make_mesh_report(Mesh{});
  EXPECT_EQ(r.triangles, 0u);
  EXPECT_EQ(r.vertices, 0u);
  EXPECT_FALSE(r.watertight);
  EXPECT_EQ(r.volume, 0.0);
}

// ---- CAD-like parts and real meshes ---------------------------------------------

// The parts made in code, through their binary STL as a user uploads them:
// closed, with the closed form's volume and area, and the Euler
// characteristic of a surface with the part's holes (V - E + F = 2 - 2g).
TEST(MeshReportParts, PartsAreWatertightWithTheirClosedFormVolumeAndArea) {
  for (const test::Part& part : test::all_parts()) {
    SCOPED_TRACE(part.name);
    const auto bytes = test::to_binary_stl(part.mesh);
    const Mesh mesh = decode_mesh(bytes, part.name);
    const MeshReport r = make_mesh_report(mesh);
    EXPECT_EQ(r.triangles, (bytes.size() - 84) / 50);
    EXPECT_EQ(r.degenerate_triangles, 0u);
    EXPECT_EQ(r.boundary_edges, 0u);
    EXPECT_EQ(r.nonmanifold_edges, 0u);
    EXPECT_EQ(r.inconsistent_edges, 0u);
    EXPECT_TRUE(r.watertight);
    // Vertices rounded to float: a few parts in 10^7.
    EXPECT_NEAR(r.volume, part.volume, 1e-6 * part.volume);
    EXPECT_NEAR(r.surface_area, part.surface_area, 1e-6 * part.surface_area);
    ASSERT_EQ(r.triangles % 2, 0u);
    const auto euler = static_cast<std::int64_t>(r.vertices) - static_cast<std::int64_t>(3 * r.triangles / 2) +
                       static_cast<std::int64_t>(r.triangles);
    EXPECT_EQ(euler, 2 - 2 * part.genus);
  }
}

// Blender's export of Wuson (assimp-testmodels STL/Wuson.stl): a real
// character mesh, open at its seams. Counted apart with numpy (welding
// bit-identical corners): 3,732 triangles on 2,117 vertices, 412 edges used
// once, 5,392 twice.
TEST(MeshReportRealMeshes, WusonIsOpenAtItsSeams) {
  const std::string path = test::assimp_model("STL/Wuson.stl");
  const MeshReport r = make_mesh_report(decode_mesh(test::read_file(path), path));
  EXPECT_EQ(r.triangles, 3732u);
  EXPECT_EQ(r.vertices, 2117u);
  EXPECT_EQ(r.boundary_edges, 412u);
  EXPECT_EQ(r.nonmanifold_edges, 0u);
  EXPECT_FALSE(r.watertight);
}

}  // namespace
}  // namespace voxd
