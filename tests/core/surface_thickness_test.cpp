// Thickness on the part's own vertices (voxd/analysis/surface_thickness.h)
// against the mesh's ray thickness at each vertex (tests/support/
// ray_thickness.h, brute force), and the PLY and glb that carry it read
// back byte by byte.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>

#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>

#include "support/ray_thickness.h"
#include "support/test_meshes.h"
#include "support/test_parts.h"
#include "voxd/analysis/surface_thickness.h"
#include "voxd/analysis/wall_thickness.h"
#include "voxd/encode/thickness_mesh.h"
#include "voxd/mesh_report.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd {
namespace {

using test::solid_of;

// A tube whose faces have rings of vertices every `step` along z (a CAD
// export's tessellation of a long face): vertices on smooth faces, not only
// on the end rims.
Mesh ringed_tube(double R, double r, double H, double step, int segments) {
  std::vector<glm::dvec2> p = {{r, 0}};
  for (double z = 0; z < H - 1e-9; z += step) p.push_back({R, z});
  for (double z = H; z > 1e-9; z -= step) p.push_back({r, z});
  return test::make_lathe(p, segments);
}

TEST(SurfaceThickness, VerticesReadTheirRayThicknessWithinAVoxel) {
  const double h = 0.05;
  struct Case {
    const char* name;
    Mesh mesh;
  };
  const std::vector<Case> cases = {
      {"ringed tube R 6 / r 4.5, turned 30/20", test::rotated(ringed_tube(6, 4.5, 4, 0.25, 192), 30, 20)},
      {"ringed tube R 5 / r 4.2, turned 47/113", test::rotated(ringed_tube(5, 4.2, 3, 0.2, 160), 47, 113)},
      {"shell R 5 / r 3.5, turned 58/141",
       test::rotated(test::concat({test::make_icosphere({0, 0, 0}, 5, 4), test::flipped(test::make_icosphere({0, 0, 0}, 3.5, 4))}),
                     58, 141)},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const Mesh welded = weld_vertices(c.mesh);
    const BitVolume v = solid_of(welded, h);
    const DenseVolume<float> map = wall_thickness(v, 2);
    const SurfaceThickness s = surface_thickness(welded, map);
    ASSERT_EQ(s.thickness.size(), welded.vertices.size());
    EXPECT_EQ(s.unresolved, 0u);
    const test::VertexAgreement a = test::compare_vertices_with_rays(welded, s.thickness, h);
    EXPECT_GE(a.vertices, 500u);
    EXPECT_GE(a.within_1, 0.95) << a.within_1 << " of " << a.vertices << " vertices compared";
  }
}

TEST(SurfaceThickness, OnlyTheFinsVerticesLieInTheThinRegion) {
  // The L-bracket of the wall-thickness tests: a 0.6 mm fin on a 3 mm base
  // beside a 2 mm upright; with min_wall 1 mm the fin is the one thin region.
  const double h = 0.1;
  const Mesh l = weld_vertices(test::make_extrusion(
      {{0, 0}, {20, 0}, {20, 3}, {12.6, 3}, {12.6, 8}, {12, 8}, {12, 3}, {2, 3}, {2, 20}, {0, 20}}, 0, 15));
  const BitVolume v = solid_of(l, h);
  const DenseVolume<float> map = wall_thickness(v, 2);
  const SurfaceThickness s = surface_thickness(l, map, static_cast<float>(1.0 / h - kWallReportTolerance), 1);
  ASSERT_EQ(s.thin_regions.size(), 1u);
  ASSERT_EQ(s.thin_region.size(), l.vertices.size());
  for (std::size_t i = 0; i < l.vertices.size(); ++i) {
    const glm::vec3 p = l.vertices[i];
    const bool fin_top = p.z > 7.9f && p.x > 11.9f && p.x < 12.7f;
    const bool base = p.z < 0.1f || (p.z < 3.1f && (p.x > 19.9f || p.x < 0.1f));
    SCOPED_TRACE(testing::Message() << "vertex " << p.x << " " << p.y << " " << p.z);
    if (fin_top) {
      EXPECT_EQ(s.thin_region[i], 1u);
      EXPECT_NEAR(s.thickness[i] * h, 0.6, h);
    }
    if (base) {
      EXPECT_EQ(s.thin_region[i], 0u);
    }
  }
}

TEST(SurfaceThickness, AFeatureUnderAVoxelReadsZero) {
  // A plate 0.02 thick at 0.1 voxels: parity fills no voxel of it.
  const Mesh plate = weld_vertices(test::make_box({0, 0, 0}, {2, 2, 0.02}));
  DenseVolume<float> map(test::make_grid({30, 30, 10}, {-0.5, -0.5, -0.5}, 0.1), 0.0f);
  const SurfaceThickness s = surface_thickness(plate, map);
  EXPECT_EQ(s.unresolved, plate.vertices.size());
  for (const float t : s.thickness) EXPECT_EQ(t, 0.0f);
}

Mesh one_triangle_pair() {
  Mesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  m.triangles = {{0, 1, 2}, {1, 3, 2}};
  return m;
}

TEST(ThicknessMesh, PlyCarriesEachVertexsPositionThicknessAndRampColour) {
  const Mesh m = one_triangle_pair();
  const std::vector<float> t = {0.0f, 1.0f, 2.0f, 3.5f};
  const ThicknessColours colours{1.0f, 3.0f};
  VectorSink sink;
  write_thickness_ply(m, t, colours, "model units", sink);
  const std::string bytes(sink.data.begin(), sink.data.end());
  const std::size_t body = bytes.find("end_header\n") + 11;
  ASSERT_NE(body, std::string::npos + 11);
  EXPECT_NE(bytes.find("element vertex 4\n"), std::string::npos);
  EXPECT_NE(bytes.find("property float thickness\n"), std::string::npos);
  EXPECT_NE(bytes.find("element face 2\n"), std::string::npos);
  ASSERT_EQ(bytes.size(), body + 4 * 19 + 2 * 13);
  const auto& ramp = thickness_ramp();
  const Rgb expected[] = {kNoMaterialColour, ramp[0], ramp[128], ramp[255]};  // 0: none; 1: low; 2: half; 3.5: clamped
  for (int i = 0; i < 4; ++i) {
    const char* v = bytes.data() + body + 19 * i;
    float xyz[3], value;
    std::memcpy(xyz, v, 12);
    std::memcpy(&value, v + 12, 4);
    EXPECT_EQ(glm::vec3(xyz[0], xyz[1], xyz[2]), m.vertices[static_cast<std::size_t>(i)]);
    EXPECT_EQ(value, t[static_cast<std::size_t>(i)]);
    EXPECT_EQ((Rgb{static_cast<std::uint8_t>(v[16]), static_cast<std::uint8_t>(v[17]), static_cast<std::uint8_t>(v[18])}),
              expected[i])
        << i;
  }
  const char* f = bytes.data() + body + 4 * 19 + 13;  // the second face
  std::int32_t idx[3];
  EXPECT_EQ(f[0], 3);
  std::memcpy(idx, f + 1, 12);
  EXPECT_EQ(idx[0], 1);
  EXPECT_EQ(idx[1], 3);
  EXPECT_EQ(idx[2], 2);
}

TEST(ThicknessMesh, GlbHoldsTheValuesAsThicknessAndTheRampAsLinearColours) {
  Mesh m = one_triangle_pair();
  m.triangles.push_back({0, 0, 1});  // degenerate: left out
  const std::vector<float> t = {0.5f, 1.0f, 2.0f, 3.0f};
  VectorSink sink;
  write_thickness_glb(m, t, ThicknessColours{1.0f, 3.0f}, "model units", sink);
  const auto& b = sink.data;
  std::uint32_t u[5];
  std::memcpy(u, b.data(), 20);
  EXPECT_EQ(u[0], 0x46546C67u);
  EXPECT_EQ(u[2], b.size());
  const nlohmann::json gltf = nlohmann::json::parse(std::string(b.begin() + 20, b.begin() + 20 + u[3]));
  const auto& prim = gltf["meshes"][0]["primitives"][0];
  const auto& acc = gltf["accessors"];
  EXPECT_EQ(acc[prim["indices"].get<int>()]["count"], 6);  // two triangles
  const std::size_t bin = 20 + u[3] + 8;
  auto floats_of = [&](const std::string& attribute, std::size_t count) {
    const auto& a = acc[prim["attributes"][attribute].get<int>()];
    const auto& view = gltf["bufferViews"][a["bufferView"].get<int>()];
    std::vector<float> out(count);
    std::memcpy(out.data(), b.data() + bin + view["byteOffset"].get<std::size_t>(), 4 * count);
    return out;
  };
  EXPECT_EQ(floats_of("_THICKNESS", 4), t);
  const std::vector<float> colours = floats_of("COLOR_0", 12);
  const Rgb last = thickness_ramp()[255];
  EXPECT_NEAR(colours[9], std::pow((last.r / 255.0 + 0.055) / 1.055, 2.4), 1e-5);
  const Rgb first = thickness_ramp()[0];  // 0.5 and 1.0 both at the low end
  EXPECT_NEAR(colours[0], colours[3], 0);
  EXPECT_NEAR(colours[4], std::pow((first.g / 255.0 + 0.055) / 1.055, 2.4), 1e-5);
  const std::vector<float> normals = floats_of("NORMAL", 12);
  EXPECT_EQ(normals[2], 1.0f);  // +z, unit
}

}  // namespace
}  // namespace voxd
