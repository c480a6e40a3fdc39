// The surfaces of results as meshes (voxd/encode/volume_surface.h) and their
// files (voxd/encode/mesh_export.h): closed and facing out (every directed
// edge once and its reverse once: no edge in four triangles), enclosing the
// filled voxels' volume exactly, or a sphere's within 1 % from a distance
// field written here; and the files read back by small readers written here.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <random>
#include <string>
#include <utility>

#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>

#include "voxd/byte_sink.h"
#include "voxd/encode/mesh_export.h"
#include "voxd/encode/volume_surface.h"
#include "support/test_meshes.h"

namespace voxd {
namespace {

// Every directed edge of the triangles: how often it is used.
std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed_edges(const Mesh& m) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> edges;
  for (const auto& t : m.triangles)
    for (int e = 0; e < 3; ++e) ++edges[{t[e], t[(e + 1) % 3]}];
  return edges;
}

// Closed and consistently oriented: each directed edge once, its reverse
// once. Returns the first edge that is not, as text ("" when all are).
std::string first_open_edge(const Mesh& m) {
  const auto edges = directed_edges(m);
  for (const auto& [e, n] : edges) {
    const auto back = edges.find({e.second, e.first});
    if (n != 1 || back == edges.end() || back->second != 1)
      return std::to_string(e.first) + "->" + std::to_string(e.second) + " used " + std::to_string(n) + ", back " +
             std::to_string(back == edges.end() ? 0 : back->second);
  }
  return "";
}

// The enclosed volume: the test meshes' divergence-theorem sum.
double enclosed(const Mesh& m) { return test::mesh_volume(m); }

Grid grid(glm::i64vec3 dims, double h = 1.0, glm::dvec3 origin = glm::dvec3(0.0)) {
  Grid g;
  g.dims = dims;
  g.voxel_size = h;
  g.origin = origin;
  return g;
}

TEST(VoxelSurface, RandomVolumesAreClosedFacingOutAndEncloseTheirVoxelsExactly) {
  std::mt19937 rng(38);
  for (const double fill : {0.1, 0.3, 0.5, 0.7, 0.9}) {
    for (int trial = 0; trial < 8; ++trial) {
      BitVolume v(grid({9, 7, 8}, 0.5, {-3.0, 2.0, 10.0}));
      std::uint64_t filled = 0, faces = 0;
      std::bernoulli_distribution on(fill);
      for (int k = 0; k < 8; ++k)
        for (int j = 0; j < 7; ++j)
          for (int i = 0; i < 9; ++i)
            if (on(rng)) v.set(i, j, k, true), ++filled;
      // Faces counted here: a filled voxel's side towards an empty one or out.
      auto at = [&](int i, int j, int k) { return i >= 0 && j >= 0 && k >= 0 && i < 9 && j < 7 && k < 8 && v.get(i, j, k); };
      for (int k = 0; k < 8; ++k)
        for (int j = 0; j < 7; ++j)
          for (int i = 0; i < 9; ++i)
            if (at(i, j, k))
              faces += !at(i + 1, j, k) + !at(i - 1, j, k) + !at(i, j + 1, k) + !at(i, j - 1, k) + !at(i, j, k + 1) +
                       !at(i, j, k - 1);
      const Mesh m = voxel_surface(v);
      SCOPED_TRACE("fill " + std::to_string(fill) + ", trial " + std::to_string(trial));
      EXPECT_EQ(boundary_face_count(v), faces);
      EXPECT_EQ(m.triangles.size(), 2 * faces);
      EXPECT_EQ(first_open_edge(m), "");
      EXPECT_NEAR(enclosed(m), filled * 0.125, 1e-6 * filled);
    }
  }
}

TEST(VoxelSurface, VoxelsMeetingAlongAnEdgeOrAtACornerStayApart) {
  // Two cubes along an edge: two closed cubes of 8 vertices each, not one
  // surface pinched along a shared edge.
  BitVolume edge(grid({2, 2, 1}));
  edge.set(0, 0, 0, true);
  edge.set(1, 1, 0, true);
  const Mesh e = voxel_surface(edge);
  EXPECT_EQ(e.vertices.size(), 16u);
  EXPECT_EQ(e.triangles.size(), 24u);
  EXPECT_EQ(first_open_edge(e), "");
  // At a corner only.
  BitVolume corner(grid({2, 2, 2}));
  corner.set(0, 0, 0, true);
  corner.set(1, 1, 1, true);
  EXPECT_EQ(voxel_surface(corner).vertices.size(), 16u);
  // The checkerboard: every voxel touches its filled neighbours along edges only.
  BitVolume board(grid({4, 4, 4}));
  int n = 0;
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 4; ++i)
        if ((i + j + k) % 2 == 0) board.set(i, j, k, true), ++n;
  const Mesh b = voxel_surface(board);
  EXPECT_EQ(b.vertices.size(), 8u * n);
  EXPECT_EQ(first_open_edge(b), "");
}

TEST(VoxelSurface, AHollowBoxHasTwoClosedSheetsTheInnerFacingIn) {
  BitVolume v(grid({6, 6, 6}, 2.0));
  for (int k = 0; k < 6; ++k)
    for (int j = 0; j < 6; ++j)
      for (int i = 0; i < 6; ++i)
        if (i == 0 || j == 0 || k == 0 || i == 5 || j == 5 || k == 5) v.set(i, j, k, true);
  const Mesh m = voxel_surface(v);
  EXPECT_EQ(first_open_edge(m), "");
  EXPECT_NEAR(enclosed(m), (216 - 64) * 8.0, 1e-9);
}

// A sphere's exact distances (negative inside), sampled at voxel centres.
DenseVolume<float> sphere_sdf(double radius, double h, bool inside_negative) {
  const int n = static_cast<int>(std::ceil(2 * radius / h)) + 4;
  const glm::dvec3 origin(-n * h / 2);
  DenseVolume<float> d(grid({n, n, n}, h, origin));
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const double r = glm::length(origin + (glm::dvec3(i, j, k) + 0.5) * h);
        d.at(i, j, k) = static_cast<float>((inside_negative ? 1 : -1) * (r - radius));
      }
  return d;
}

TEST(ZeroLevelSet, ASpheresDistancesGiveAClosedSurfaceEnclosingItsVolumeWithinOnePercent) {
  for (const bool inside_negative : {true, false}) {
    const double radius = 7.5, h = 0.5;  // 15 voxels across
    const Mesh m = zero_level_set(sphere_sdf(radius, h, inside_negative), inside_negative, static_cast<float>(h / 2));
    EXPECT_EQ(first_open_edge(m), "");
    const double exact = 4.0 / 3.0 * M_PI * radius * radius * radius;
    EXPECT_NEAR(enclosed(m), exact, 0.01 * exact) << (inside_negative ? "inside negative" : "inside positive");
    // Every vertex near the sphere: within half a voxel.
    for (const glm::vec3& p : m.vertices) EXPECT_NEAR(glm::length(glm::dvec3(p)), radius, h / 2);
  }
}

TEST(ZeroLevelSet, APartFillingItsGridIsClosedByTheOutsideBeyondIt) {
  DenseVolume<float> d(grid({3, 4, 5}, 1.0), -1.0f);  // all inside
  const Mesh m = zero_level_set(d, true, 0.5f);
  EXPECT_EQ(first_open_edge(m), "");
  // Every sample reads -1, the outside +0.5 a voxel beyond: each face
  // crosses 2/3 of a voxel past the outermost centres (the edges and
  // corners cut off), so the part holds the box of its centres and lies in
  // that box grown by 2/3 each side.
  const double grow = 4.0 / 3.0;
  EXPECT_GT(enclosed(m), 2.0 * 3.0 * 4.0);
  EXPECT_LT(enclosed(m), (2 + grow) * (3 + grow) * (4 + grow));
  for (const glm::vec3& p : m.vertices) {
    EXPECT_GE(p.x, 0.5 - 2.0 / 3.0 - 1e-5);
    EXPECT_LE(p.x, 2.5 + 2.0 / 3.0 + 1e-5);
  }
}

TEST(ZeroLevelSet, NoSurfaceWhereNoSampleIsInside) {
  DenseVolume<float> d(grid({4, 4, 4}), 2.0f);
  const Mesh m = zero_level_set(d, true, 0.5f);
  EXPECT_TRUE(m.vertices.empty());
  EXPECT_TRUE(m.triangles.empty());
}

Mesh two_cubes() {
  BitVolume v(grid({3, 1, 1}, 0.25, {1, 2, 3}));
  v.set(0, 0, 0, true);
  v.set(2, 0, 0, true);
  return voxel_surface(v);
}

TEST(MeshExport, BinarySTLHoldsEveryTriangleWithItsUnitNormal) {
  const Mesh m = two_cubes();
  VectorSink sink;
  write_mesh_stl(m, "voxel surface", sink);
  const auto& b = sink.data;
  ASSERT_EQ(b.size(), 84 + 50 * m.triangles.size());
  EXPECT_NE(std::string(reinterpret_cast<const char*>(b.data()), 5), "solid");
  std::uint32_t count;
  std::memcpy(&count, b.data() + 80, 4);
  EXPECT_EQ(count, m.triangles.size());
  for (std::size_t t = 0; t < count; ++t) {
    float f[12];
    std::memcpy(f, b.data() + 84 + 50 * t, sizeof f);
    const glm::vec3 n(f[0], f[1], f[2]), a(f[3], f[4], f[5]), c1(f[6], f[7], f[8]), c2(f[9], f[10], f[11]);
    EXPECT_EQ(a, m.vertices[m.triangles[t][0]]);
    EXPECT_NEAR(glm::dot(n, glm::normalize(glm::cross(c1 - a, c2 - a))), 1.0, 1e-6);
  }
}

TEST(MeshExport, PLYHoldsTheIndexedMesh) {
  const Mesh m = two_cubes();
  VectorSink sink;
  write_mesh_ply(m, "voxel surface", sink);
  const std::string text(sink.data.begin(), sink.data.end());
  const std::string header_end = "end_header\n";
  const std::size_t body = text.find(header_end) + header_end.size();
  EXPECT_NE(text.find("element vertex 16\n"), std::string::npos);
  EXPECT_NE(text.find("element face 24\n"), std::string::npos);
  ASSERT_EQ(text.size(), body + 12 * 16 + 13 * 24);
  Mesh back;
  for (int v = 0; v < 16; ++v) {
    glm::vec3 p;
    std::memcpy(&p, text.data() + body + 12 * v, 12);
    back.vertices.push_back(p);
  }
  for (int t = 0; t < 24; ++t) {
    const char* at = text.data() + body + 12 * 16 + 13 * t;
    ASSERT_EQ(at[0], 3);
    std::int32_t c[3];
    std::memcpy(c, at + 1, 12);
    back.triangles.push_back({static_cast<std::uint32_t>(c[0]), static_cast<std::uint32_t>(c[1]), static_cast<std::uint32_t>(c[2])});
  }
  EXPECT_EQ(first_open_edge(back), "");
  EXPECT_NEAR(enclosed(back), 2 * 0.25 * 0.25 * 0.25, 1e-9);
}

TEST(MeshExport, GLBHoldsPositionsAndIndicesWithTheirBounds) {
  const Mesh m = two_cubes();
  VectorSink sink;
  write_mesh_glb(m, "voxel surface", sink);
  const auto& b = sink.data;
  std::uint32_t head[5];
  std::memcpy(head, b.data(), sizeof head);
  EXPECT_EQ(head[0], 0x46546C67u);
  EXPECT_EQ(head[2], b.size());
  EXPECT_EQ(head[3] % 4, 0u);
  const auto gltf = nlohmann::json::parse(std::string(b.begin() + 20, b.begin() + 20 + head[3]));
  EXPECT_EQ(gltf["accessors"][0]["count"], 16);
  EXPECT_EQ(gltf["accessors"][1]["count"], 72);
  EXPECT_EQ(gltf["accessors"][0]["min"], nlohmann::json::array({1.0, 2.0, 3.0}));
  EXPECT_EQ(gltf["accessors"][0]["max"], nlohmann::json::array({1.75, 2.25, 3.25}));
  EXPECT_EQ(b.size(), 20 + head[3] + 8 + 12 * 16 + 12 * 24);
  // An empty surface is an empty scene, which glTF allows.
  VectorSink empty;
  write_mesh_glb(Mesh{}, "nothing", empty);
  std::uint32_t json_length;
  std::memcpy(&json_length, empty.data.data() + 12, 4);
  EXPECT_FALSE(nlohmann::json::parse(std::string(empty.data.begin() + 20, empty.data.begin() + 20 + json_length))
                   .contains("buffers"));
}

}  // namespace
}  // namespace voxd
