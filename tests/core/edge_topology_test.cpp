// The fast edge count (count_edge_topology, hashing without welding)
// against the count of the welded mesh (edge_topology_of_welded, which the
// mesh report reads: vertex indices grouped by vertex, no hash): the same
// edges, boundary, non-manifold and inconsistent edges, and the same volume
// summed in the same order, on CAD parts, parts with holes punched and
// triangles flipped, soups, a mesh of several chunks, and real open files of
// assimp-testmodels, on one thread and several; and edge counts known by
// hand.
#include <string>

#include <gtest/gtest.h>

#include "support/assimp_models.h"
#include "support/test_meshes.h"
#include "support/test_parts.h"
#include "voxd/edge_topology.h"
#include "voxd/mesh_io/mesh_decode.h"
#include "voxd/mesh_report.h"

namespace voxd {
namespace {

void expect_same_as_report(const Mesh& mesh, const std::string& what) {
  const MeshReport report = make_mesh_report(mesh);
  const EdgeTopology welded = edge_topology_of_welded(weld_vertices(mesh));
  EXPECT_EQ(welded.boundary_edges, report.boundary_edges) << what;
  EXPECT_EQ(welded.nonmanifold_edges, report.nonmanifold_edges) << what;
  EXPECT_EQ(welded.inconsistent_edges, report.inconsistent_edges) << what;
  for (int threads : {1, 3}) {
    const EdgeTopology t = count_edge_topology(mesh, threads);
    EXPECT_EQ(t.edges, welded.edges) << what << " threads " << threads;
    EXPECT_EQ(t.six_volume, welded.six_volume) << what << " threads " << threads;
    EXPECT_EQ(t.boundary_edges, report.boundary_edges) << what << " threads " << threads;
    EXPECT_EQ(t.nonmanifold_edges, report.nonmanifold_edges) << what;
    EXPECT_EQ(t.inconsistent_edges, report.inconsistent_edges) << what;
    EXPECT_EQ(t.closed(), report.boundary_edges == 0 && report.nonmanifold_edges == 0) << what;
    if (report.watertight) {
      EXPECT_NEAR(t.six_volume / 6.0, report.volume, 1e-6 * std::abs(report.volume)) << what;
    }
  }
}

using test::soup_of;

TEST(EdgeTopology, CountsAsTheMeshReportDoesOnPartsWholeOpenAndFlipped) {
  for (const test::Part& part : test::all_parts()) {
    expect_same_as_report(part.mesh, part.name);
    expect_same_as_report(soup_of(part.mesh), part.name + " as a soup");
    expect_same_as_report(test::punched(part.mesh, 41), part.name + " punched");
    Mesh flipped_some = part.mesh;
    for (std::size_t t = 0; t < flipped_some.triangles.size(); t += 9)
      std::swap(flipped_some.triangles[t][1], flipped_some.triangles[t][2]);
    expect_same_as_report(flipped_some, part.name + " with triangles flipped");
    // Two copies touching along every edge: every edge used four times.
    expect_same_as_report(test::concat({part.mesh, part.mesh}), part.name + " twice");
  }
}

TEST(EdgeTopology, AnInsideOutClosedMeshHasANegativeVolume) {
  const Mesh box = test::flipped(test::make_box({1, 2, 3}, {5, 5, 5}));
  for (const EdgeTopology& t : {count_edge_topology(box), edge_topology_of_welded(weld_vertices(box))}) {
    EXPECT_TRUE(t.closed());
    EXPECT_EQ(t.edges, 18u);  // a box's 12 triangles: 12 * 3 / 2
    EXPECT_EQ(t.inconsistent_edges, 0u);
    EXPECT_DOUBLE_EQ(t.six_volume, -6.0 * 24.0);
  }
}

TEST(EdgeTopology, ASingleTriangleHasThreeBoundaryEdges) {
  Mesh triangle;
  triangle.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  triangle.triangles = {{0, 1, 2}};
  for (const EdgeTopology& t : {count_edge_topology(triangle), edge_topology_of_welded(triangle)}) {
    EXPECT_EQ(t.edges, 3u);
    EXPECT_EQ(t.boundary_edges, 3u);
    EXPECT_FALSE(t.closed());
  }
}

// More triangles than one chunk of the volume's sum (16,384): the welded
// count adds the chunks as the parallel one does.
TEST(EdgeTopology, AMeshOfSeveralChunksCountsAlike) {
  const Mesh torus = test::make_torus({0.3f, -0.2f, 0.1f}, 40, 10, 200, 120);
  ASSERT_GT(torus.triangles.size(), 2u * 16384u);
  expect_same_as_report(torus, "torus");
  expect_same_as_report(soup_of(test::punched(torus, 97)), "torus punched, as a soup");
}

TEST(EdgeTopology, SkipsTrianglesWithTwoCornersAtOnePositionAsTheReportDoes) {
  Mesh box = test::make_box({0, 0, 0}, {1, 1, 1});
  box.vertices.push_back(box.vertices[0]);  // a second vertex at corner 0's position
  box.triangles.push_back({0, static_cast<std::uint32_t>(box.vertices.size() - 1), 1});
  box.vertices.push_back(glm::vec3(-0.0f, 0.0f, 0.0f));  // -0 is 0
  box.triangles.push_back({0, static_cast<std::uint32_t>(box.vertices.size() - 1), 2});
  expect_same_as_report(box, "box with degenerate triangles");
  EXPECT_TRUE(count_edge_topology(box).closed());
}

TEST(EdgeTopology, CountsAsTheMeshReportDoesOnRealOpenFiles) {
  for (const char* file : {"STL/Spider_binary.stl", "STL/Wuson.stl", "STL/sphereWithHole.stl", "OBJ/regr01.obj",
                           "OBJ/box_longline.obj", "OBJ/concave_polygon.obj", "PLY/cube.ply"}) {
    const Mesh mesh = decode_mesh(test::read_file(test::assimp_model(file)), file);
    expect_same_as_report(mesh, file);
  }
}

TEST(EdgeTopology, AnEmptyMeshHasNoEdges) {
  for (const EdgeTopology& t : {count_edge_topology(Mesh{}), edge_topology_of_welded(Mesh{})}) {
    EXPECT_EQ(t.edges + t.boundary_edges + t.nonmanifold_edges + t.inconsistent_edges, 0u);
    EXPECT_EQ(t.six_volume, 0.0);
  }
}

}  // namespace
}  // namespace voxd
