// Palette reconstructions as STL and GLB: read back with small readers
// written here, then the triangle counts, the enclosed volume, the
// instancing and the glTF bookkeeping (accessor bounds, alignment, chunk
// padding) checked against what the volume says they must be.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <random>
#include <set>
#include <string>
#include <tuple>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>
#include <nlohmann/json.hpp>

#include "voxd/error.h"
#include "voxd/encode/palette_export.h"
#include "voxd/voxelize/palette_geometry.h"

namespace voxd {
namespace {

using nlohmann::json;

enum : std::uint8_t { kEmpty = 0, kFull = 1, kWedge = 2, kTetra = 3 };

// builtin_palette is implemented elsewhere; these four are all the writers
// need to see: nothing, a cube, and two partial elements.
Palette test_palette() {
  Palette p;
  p.elements.push_back({"empty", {}});
  p.elements.push_back({"full", {ConvexPiece{}}});
  p.elements.push_back({"wedge", {ConvexPiece{HalfSpace{{1, 1, 0}, 1}}}});
  p.elements.push_back({"tetra", {ConvexPiece{HalfSpace{{1, 1, 1}, 1}}}});
  return p;
}

Grid make_grid(glm::i64vec3 dims, double size, glm::dvec3 origin) {
  Grid g;
  g.dims = dims;
  g.voxel_size = size;
  g.origin = origin;
  return g;
}

DenseVolume<std::uint8_t> random_volume(const Grid& grid, std::uint64_t seed) {
  DenseVolume<std::uint8_t> v(grid);
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> pick(0, 3);
  for (auto& e : v.values()) e = static_cast<std::uint8_t>(pick(rng));
  return v;
}

bool full_at(const DenseVolume<std::uint8_t>& v, std::int64_t i, std::int64_t j, std::int64_t k) {
  const glm::i64vec3 d = v.grid().dims;
  if (i < 0 || j < 0 || k < 0 || i >= d.x || j >= d.y || k >= d.z) return false;
  return v.at(i, j, k) == kFull;
}

int exposed_faces(const DenseVolume<std::uint8_t>& v, std::int64_t i, std::int64_t j, std::int64_t k) {
  return !full_at(v, i - 1, j, k) + !full_at(v, i + 1, j, k) + !full_at(v, i, j - 1, k) + !full_at(v, i, j + 1, k) +
         !full_at(v, i, j, k - 1) + !full_at(v, i, j, k + 1);
}

// ------------------------------------------------------------ STL reader --

struct StlTriangle {
  glm::vec3 normal;
  glm::vec3 v[3];
};

std::uint32_t read_u32(const std::vector<std::uint8_t>& b, std::size_t at) {
  std::uint32_t x;
  std::memcpy(&x, b.data() + at, 4);
  return x;
}

std::vector<StlTriangle> read_stl(const std::vector<std::uint8_t>& bytes, std::uint32_t* header_count) {
  EXPECT_GE(bytes.size(), 84u);
  *header_count = read_u32(bytes, 80);
  EXPECT_EQ(bytes.size(), 84u + 50u * *header_count) << "file size disagrees with the header's count";
  EXPECT_NE(std::string(bytes.begin(), bytes.begin() + 5), "solid");
  std::vector<StlTriangle> tris((bytes.size() - 84) / 50);
  for (std::size_t t = 0; t < tris.size(); ++t) {
    float f[12];
    std::memcpy(f, bytes.data() + 84 + 50 * t, sizeof f);
    tris[t].normal = {f[0], f[1], f[2]};
    for (int c = 0; c < 3; ++c) tris[t].v[c] = {f[3 + 3 * c], f[4 + 3 * c], f[5 + 3 * c]};
    std::uint16_t attribute;
    std::memcpy(&attribute, bytes.data() + 84 + 50 * t + 48, 2);
    EXPECT_EQ(attribute, 0);
  }
  return tris;
}

// Divergence theorem, about a point near the part so float coordinates far
// from the origin do not cost digits.
double signed_volume(const std::vector<StlTriangle>& tris, const glm::dvec3& about) {
  double six_v = 0.0;
  for (const StlTriangle& t : tris) {
    const glm::dvec3 a = glm::dvec3(t.v[0]) - about, b = glm::dvec3(t.v[1]) - about, c = glm::dvec3(t.v[2]) - about;
    six_v += glm::dot(a, glm::cross(b, c));
  }
  return six_v / 6.0;
}

// Facet normals are unit and agree with the corners' winding.
void expect_normals(const std::vector<StlTriangle>& tris) {
  for (const StlTriangle& t : tris) {
    EXPECT_NEAR(glm::length(t.normal), 1.0f, 1e-5f);
    const glm::dvec3 n = glm::cross(glm::dvec3(t.v[1] - t.v[0]), glm::dvec3(t.v[2] - t.v[0]));
    EXPECT_GT(glm::dot(glm::normalize(n), glm::dvec3(t.normal)), 0.999);
  }
}

TEST(PaletteStl, SolidBlockKeepsOnlyItsOuterFaces) {
  const double s = 0.5;
  const glm::dvec3 origin(10, -20, 30);
  DenseVolume<std::uint8_t> v(make_grid({3, 3, 3}, s, origin), kFull);
  VectorSink sink;
  write_palette_stl(test_palette(), v, sink);
  std::uint32_t count = 0;
  const auto tris = read_stl(sink.data, &count);
  EXPECT_EQ(count, 6u * 9u * 2u);
  EXPECT_NEAR(signed_volume(tris, origin), 27 * s * s * s, 1e-9);
  expect_normals(tris);
  // Closed: every directed edge (by exact float corners) has its reverse.
  std::map<std::tuple<float, float, float, float, float, float>, int> edges;
  for (const auto& t : tris)
    for (int c = 0; c < 3; ++c) {
      const glm::vec3 a = t.v[c], b = t.v[(c + 1) % 3];
      ++edges[{a.x, a.y, a.z, b.x, b.y, b.z}];
    }
  for (const auto& [e, n] : edges) {
    EXPECT_EQ(n, 1);
    const auto [ax, ay, az, bx, by, bz] = e;
    const auto twin = edges.find({bx, by, bz, ax, ay, az});
    EXPECT_TRUE(twin != edges.end() && twin->second == 1);
  }
  // Every corner lies on the block's boundary box.
  for (const auto& t : tris)
    for (const glm::vec3& c : t.v)
      for (int a = 0; a < 3; ++a) {
        EXPECT_GE(c[a], static_cast<float>(origin[a]));
        EXPECT_LE(c[a], static_cast<float>(origin[a] + 3 * s));
      }
}

TEST(PaletteStl, MixedVolumeCountsAndEnclosesTheElementVolumes) {
  const Palette palette = test_palette();
  const glm::dvec3 scale(1.0, 2.0, 0.5);
  const double s = 0.3;
  const glm::dvec3 origin(-1, 2, 5);
  const DenseVolume<std::uint8_t> v = random_volume(make_grid({5, 4, 3}, s, origin), 3);
  std::uint64_t expected = 0;
  double volume = 0.0;
  const double cell = s * s * s * scale.x * scale.y * scale.z;
  for (std::int64_t k = 0; k < 3; ++k)
    for (std::int64_t j = 0; j < 4; ++j)
      for (std::int64_t i = 0; i < 5; ++i) {
        const std::uint8_t e = v.at(i, j, k);
        expected += e == kFull ? 2 * exposed_faces(v, i, j, k) : e == kWedge ? 8 : e == kTetra ? 4 : 0;
        volume += element_volume(palette.elements[e]) * cell;
      }
  VectorSink sink;
  write_palette_stl(palette, v, scale, sink);
  std::uint32_t count = 0;
  const auto tris = read_stl(sink.data, &count);
  EXPECT_EQ(tris.size(), count);
  EXPECT_EQ(count, expected);
  EXPECT_GT(volume, 0.0);
  EXPECT_NEAR(signed_volume(tris, origin * scale), volume, 1e-5 * volume);
  expect_normals(tris);
  // The grid's space stretched per axis, origin included: everything in
  // [origin, origin + dims * size] * scale.
  for (const auto& t : tris)
    for (const glm::vec3& c : t.v) {
      EXPECT_GE(c.x, static_cast<float>(origin.x * scale.x) - 1e-5f);
      EXPECT_GE(c.z, static_cast<float>(origin.z * scale.z) - 1e-5f);
      EXPECT_LE(c.x, static_cast<float>((origin.x + 5 * s) * scale.x) + 1e-5f);
      EXPECT_LE(c.y, static_cast<float>((origin.y + 4 * s) * scale.y) + 1e-5f);
      EXPECT_LE(c.z, static_cast<float>((origin.z + 3 * s) * scale.z) + 1e-5f);
    }
}

TEST(PaletteStl, EmptyVolumeHasNoTriangles) {
  DenseVolume<std::uint8_t> v(make_grid({4, 4, 4}, 1.0, glm::dvec3(0.0)), kEmpty);
  VectorSink sink;
  write_palette_stl(test_palette(), v, sink);
  std::uint32_t count = 1;
  EXPECT_TRUE(read_stl(sink.data, &count).empty());
  EXPECT_EQ(count, 0u);
}

TEST(PaletteStl, LargeVolumesAreStreamedInPieces) {
  // Count writes: slabs are flushed as they fill, never as one write.
  struct CountingSink final : ByteSink {
    using ByteSink::write;
    void write(std::span<const std::uint8_t> bytes) override {
      ++writes;
      data.insert(data.end(), bytes.begin(), bytes.end());
    }
    int writes = 0;
    std::vector<std::uint8_t> data;
  } sink;
  const DenseVolume<std::uint8_t> v = random_volume(make_grid({40, 40, 40}, 1.0, glm::dvec3(0.0)), 5);
  write_palette_stl(test_palette(), v, sink);
  EXPECT_GT(sink.writes, 2);
  std::uint32_t count = 0;
  EXPECT_EQ(read_stl(sink.data, &count).size(), count);
}

TEST(PaletteExport, BadInputsAreRejected) {
  VectorSink sink;
  DenseVolume<std::uint8_t> v(make_grid({2, 2, 2}, 1.0, glm::dvec3(0.0)), kFull);
  v.at(1, 1, 1) = 4;  // the palette has 4 elements
  for (int format = 0; format < 2; ++format) {
    const auto write = [&](const DenseVolume<std::uint8_t>& vol, glm::dvec3 scale) {
      if (format == 0) write_palette_stl(test_palette(), vol, scale, sink);
      else write_palette_glb(test_palette(), vol, scale, sink);
    };
    for (const glm::dvec3 scale : {glm::dvec3(1.0), glm::dvec3(1, 0, 1), glm::dvec3(1, 1, -2), glm::dvec3(NAN, 1, 1)}) {
      try {
        write(v, scale);
        FAIL() << "expected invalid_argument";
      } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::invalid_argument);
      }
    }
    EXPECT_THROW(write(DenseVolume<std::uint8_t>(), glm::dvec3(1.0)), Error);
  }
  EXPECT_TRUE(sink.data.empty()) << "nothing is written before the checks pass";
}

// ------------------------------------------------------------ GLB reader --

struct Glb {
  json gltf;
  std::vector<std::uint8_t> bin;
  bool has_bin = false;
};

Glb read_glb(const std::vector<std::uint8_t>& bytes) {
  Glb glb;
  EXPECT_GE(bytes.size(), 20u);
  EXPECT_EQ(read_u32(bytes, 0), 0x46546C67u);  // "glTF"
  EXPECT_EQ(read_u32(bytes, 4), 2u);
  EXPECT_EQ(read_u32(bytes, 8), bytes.size());
  const std::uint32_t json_length = read_u32(bytes, 12);
  EXPECT_EQ(read_u32(bytes, 16), 0x4E4F534Au);  // "JSON"
  EXPECT_EQ(json_length % 4, 0u);
  EXPECT_LE(20u + json_length, bytes.size());
  const std::string text(bytes.begin() + 20, bytes.begin() + 20 + json_length);
  // Padding is spaces, after the closing brace.
  EXPECT_EQ(text.find_last_not_of(' '), text.rfind('}'));
  glb.gltf = json::parse(text);
  std::size_t at = 20 + json_length;
  if (at < bytes.size()) {
    const std::uint32_t bin_length = read_u32(bytes, at);
    EXPECT_EQ(read_u32(bytes, at + 4), 0x004E4942u);  // "BIN\0"
    EXPECT_EQ(bin_length % 4, 0u);
    EXPECT_EQ(at + 8 + bin_length, bytes.size());
    glb.bin.assign(bytes.begin() + static_cast<std::ptrdiff_t>(at + 8), bytes.end());
    glb.has_bin = true;
  }
  return glb;
}

// An accessor's VEC3 float values, after checking that its view is aligned,
// in the buffer, and just big enough, and that its min/max (required for
// POSITION, written for all) are the values' exact extent.
std::vector<glm::vec3> read_vec3(const Glb& glb, std::size_t accessor) {
  const json& a = glb.gltf["accessors"][accessor];
  EXPECT_EQ(a["componentType"], 5126);
  EXPECT_EQ(a["type"], "VEC3");
  const json& view = glb.gltf["bufferViews"][a["bufferView"].get<std::size_t>()];
  const std::size_t offset = view["byteOffset"].get<std::size_t>() + a.value("byteOffset", std::size_t{0});
  const std::size_t count = a["count"];
  EXPECT_EQ(view["buffer"], 0);
  EXPECT_EQ(offset % 4, 0u);
  EXPECT_EQ(view["byteLength"].get<std::size_t>(), 12 * count);
  EXPECT_LE(offset + 12 * count, glb.gltf["buffers"][0]["byteLength"].get<std::size_t>());
  EXPECT_LE(glb.gltf["buffers"][0]["byteLength"].get<std::size_t>(), glb.bin.size());
  std::vector<glm::vec3> values(count);
  if (offset + 12 * count <= glb.bin.size()) std::memcpy(values.data(), glb.bin.data() + offset, 12 * count);
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  for (const glm::vec3& p : values) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  EXPECT_TRUE(a.contains("min") && a.contains("max"));
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(a["min"][c].get<float>(), lo[c]) << "accessor " << accessor;
    EXPECT_EQ(a["max"][c].get<float>(), hi[c]) << "accessor " << accessor;
  }
  return values;
}

TEST(PaletteGlb, InstancesEveryVoxelOfAPartialElementAndExposedFullOnes) {
  const Palette palette = test_palette();
  const glm::dvec3 scale(1.0, 1.0, 2.5);
  const double s = 0.25;
  const glm::dvec3 origin(3, -4, 7);
  const glm::dvec3 size = s * scale;
  DenseVolume<std::uint8_t> v = random_volume(make_grid({6, 5, 4}, s, origin), 9);
  // A solid 3x3x3 block so some full voxels are hidden.
  for (int k = 0; k < 3; ++k)
    for (int j = 1; j < 4; ++j)
      for (int i = 1; i < 4; ++i) v.at(i, j, k) = kFull;
  ASSERT_EQ(exposed_faces(v, 2, 2, 1), 0);

  // What each element's node must place: voxel corners, as floats.
  std::map<std::string, std::multiset<std::tuple<float, float, float>>> expected;
  for (std::int64_t k = 0; k < 4; ++k)
    for (std::int64_t j = 0; j < 5; ++j)
      for (std::int64_t i = 0; i < 6; ++i) {
        const std::uint8_t e = v.at(i, j, k);
        if (e == kEmpty || (e == kFull && exposed_faces(v, i, j, k) == 0)) continue;
        const glm::vec3 c(origin * scale + glm::dvec3(i, j, k) * size);
        expected[palette.elements[e].name].insert({c.x, c.y, c.z});
      }
  ASSERT_EQ(expected.size(), 3u);

  VectorSink sink;
  write_palette_glb(palette, v, scale, sink);
  const Glb glb = read_glb(sink.data);
  const json& g = glb.gltf;
  ASSERT_TRUE(glb.has_bin);
  EXPECT_EQ(g["asset"]["version"], "2.0");
  EXPECT_EQ(g["asset"]["generator"], "voxd");
  ASSERT_TRUE(g.contains("extensionsUsed"));
  EXPECT_NE(std::find(g["extensionsUsed"].begin(), g["extensionsUsed"].end(), "EXT_mesh_gpu_instancing"),
            g["extensionsUsed"].end());
  // Required: a viewer without instancing must not draw it wrong.
  EXPECT_EQ(g["extensionsRequired"], json::array({"EXT_mesh_gpu_instancing"}));
  for (const json& view : g["bufferViews"]) {
    EXPECT_EQ(view["byteOffset"].get<std::size_t>() % 4, 0u);
    EXPECT_EQ(view["byteLength"].get<std::size_t>() % 4, 0u);
  }
  // The BIN chunk's padding (if any) is zeros.
  const std::size_t used_bin = g["buffers"][0]["byteLength"];
  for (std::size_t b = used_bin; b < glb.bin.size(); ++b) EXPECT_EQ(glb.bin[b], 0);

  // One root node in the scene turns the Z-up model to glTF's Y-up: model
  // +z ends up along glTF +y, model +y along glTF -z.
  ASSERT_EQ(g["nodes"].size(), 4u);
  const json& scene_nodes = g["scenes"][g["scene"].get<std::size_t>()]["nodes"];
  ASSERT_EQ(scene_nodes.size(), 1u);
  const json& root = g["nodes"][scene_nodes[0].get<std::size_t>()];
  ASSERT_EQ(root["children"].size(), 3u);
  const glm::dquat turn(root["rotation"][3].get<double>(), root["rotation"][0].get<double>(), root["rotation"][1].get<double>(),
                        root["rotation"][2].get<double>());
  EXPECT_NEAR(glm::length(turn), 1.0, 1e-12);
  const glm::dvec3 up = turn * glm::dvec3(0, 0, 1), depth = turn * glm::dvec3(0, 1, 0), x = turn * glm::dvec3(1, 0, 0);
  EXPECT_NEAR(glm::distance(up, glm::dvec3(0, 1, 0)), 0.0, 1e-12);
  EXPECT_NEAR(glm::distance(depth, glm::dvec3(0, 0, -1)), 0.0, 1e-12);
  EXPECT_NEAR(glm::distance(x, glm::dvec3(1, 0, 0)), 0.0, 1e-12);
  std::set<std::string> seen;
  for (const json& child : root["children"]) {
    const json& node = g["nodes"][child.get<std::size_t>()];
    const std::string name = node["name"];
    SCOPED_TRACE(name);
    seen.insert(name);
    const std::size_t e = palette.find(name).value_or(0);
    ASSERT_TRUE(expected.count(name));
    const std::size_t translation = node["extensions"]["EXT_mesh_gpu_instancing"]["attributes"]["TRANSLATION"];
    EXPECT_EQ(g["accessors"][translation]["count"].get<std::size_t>(), expected[name].size());
    std::multiset<std::tuple<float, float, float>> placed;
    for (const glm::vec3& t : read_vec3(glb, translation)) placed.insert({t.x, t.y, t.z});
    EXPECT_EQ(placed, expected[name]);

    // The mesh: flat triangles, pre-scaled into the stretched voxel, whose
    // volume is the element's share of it.
    const json& mesh = g["meshes"][node["mesh"].get<std::size_t>()];
    ASSERT_EQ(mesh["primitives"].size(), 1u);
    const json& primitive = mesh["primitives"][0];
    EXPECT_EQ(primitive.value("mode", 4), 4);
    EXPECT_FALSE(primitive.contains("indices"));
    const auto positions = read_vec3(glb, primitive["attributes"]["POSITION"]);
    const auto normals = read_vec3(glb, primitive["attributes"]["NORMAL"]);
    ASSERT_EQ(positions.size(), normals.size());
    ASSERT_EQ(positions.size() % 3, 0u);
    double six_v = 0.0;
    for (std::size_t t = 0; t < positions.size(); t += 3) {
      const glm::dvec3 a(positions[t]), b(positions[t + 1]), c(positions[t + 2]);
      six_v += glm::dot(a, glm::cross(b, c));
      const glm::dvec3 n = glm::normalize(glm::cross(b - a, c - a));
      for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(normals[t + k], normals[t]) << "flat shading: one normal per triangle";
        EXPECT_GT(glm::dot(glm::dvec3(normals[t + k]), n), 0.999);
      }
      for (const glm::dvec3& p : {a, b, c})
        for (int ax = 0; ax < 3; ++ax) {
          EXPECT_GE(p[ax], -1e-6);
          EXPECT_LE(p[ax], size[ax] + 1e-6);
        }
    }
    EXPECT_NEAR(six_v / 6.0, element_volume(palette.elements[e]) * size.x * size.y * size.z, 1e-6);
    if (e == kFull) {
      EXPECT_EQ(positions.size(), 36u);
    }
  }
  EXPECT_EQ(seen.size(), 3u) << "one node per used element";
}

TEST(PaletteGlb, FullyHiddenFullElementIsNotInstanced) {
  // Only the centre of a 3x3x3 full block is hidden; 26 exposed instances.
  DenseVolume<std::uint8_t> v(make_grid({3, 3, 3}, 1.0, glm::dvec3(0.0)), kFull);
  VectorSink sink;
  write_palette_glb(test_palette(), v, sink);
  const Glb glb = read_glb(sink.data);
  ASSERT_EQ(glb.gltf["nodes"].size(), 2u);  // the element's, and the root turning it Y-up
  const std::size_t translation =
      glb.gltf["nodes"][0]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"]["TRANSLATION"];
  const auto placed = read_vec3(glb, translation);
  EXPECT_EQ(placed.size(), 26u);
  EXPECT_EQ(std::count(placed.begin(), placed.end(), glm::vec3(1, 1, 1)), 0);
}

TEST(PaletteGlb, EmptyVolumeIsAValidEmptyScene) {
  DenseVolume<std::uint8_t> v(make_grid({2, 3, 4}, 1.0, glm::dvec3(0.0)), kEmpty);
  VectorSink sink;
  write_palette_glb(test_palette(), v, sink);
  const Glb glb = read_glb(sink.data);
  EXPECT_FALSE(glb.has_bin);
  EXPECT_EQ(glb.gltf["asset"]["version"], "2.0");
  EXPECT_FALSE(glb.gltf.contains("nodes"));
  EXPECT_FALSE(glb.gltf.contains("buffers"));
  EXPECT_EQ(glb.gltf["scenes"].size(), 1u);
}

}  // namespace
}  // namespace voxd
