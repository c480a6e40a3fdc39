// The decoders on a real corpus: every STL, OBJ and PLY file of Debian's
// assimp-testmodels (the Open Asset Import Library's own test files, from
// Blender, 3ds Max, trueSpace, VCG and hand-written regressions) has its
// expected outcome here: what it decodes to, or the exact problem and the
// line it names. A file of the corpus missing from the table fails the test,
// so none is left unread.
//
// The counts were made apart from voxd, with a short numpy script: triangles
// from the STL record count, the PLY face lists, or the OBJ faces
// fan-triangulated without the triangles whose corners repeat; boundary and
// non-manifold edges from the corners welded where bit-identical.
#include <algorithm>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "support/assimp_models.h"
#include "support/test_meshes.h"
#include "voxd/error.h"
#include "voxd/mesh_io/mesh_decode.h"
#include "voxd/mesh_report.h"

namespace voxd {
namespace {

struct Decodes {
  MeshFormat format;
  std::uint64_t triangles, vertices;
  bool watertight;
  std::uint64_t boundary_edges, nonmanifold_edges;
  const char* warning = nullptr;  // a fragment of the one warning, if any
};

struct Refused {
  ErrorCode code;
  const char* message;  // a fragment that names the line or count
};

struct Expected {
  std::optional<Decodes> decodes;
  std::optional<Refused> refused;
};

Expected ok(MeshFormat f, std::uint64_t t, std::uint64_t v, bool w, std::uint64_t b, std::uint64_t n,
            const char* warning = nullptr) {
  return {Decodes{f, t, v, w, b, n, warning}, std::nullopt};
}
Expected refused(ErrorCode code, const char* message) { return {std::nullopt, Refused{code, message}}; }

using F = MeshFormat;
using E = ErrorCode;

const std::map<std::string, Expected>& corpus() {
  static const std::map<std::string, Expected> table = {
      // 3ds Max's binary STL: 16 edges shared by three faces.
      {"STL/3DSMaxExport.STL", ok(F::stl_binary, 2000, 1042, false, 0, 16)},
      // trueSpace's spider, ASCII and binary twins: 56 faces with a repeated
      // corner, 72 open edges.
      {"STL/Spider_ascii.stl", ok(F::stl_ascii, 1368, 722, false, 72, 0)},
      {"STL/Spider_binary.stl", ok(F::stl_binary, 1368, 722, false, 72, 0)},
      {"STL/Wuson.stl", ok(F::stl_binary, 3732, 2117, false, 412, 0)},
      // No extension: told by its content.
      {"STL/formatDetection", ok(F::stl_ascii, 1, 3, false, 3, 0)},
      {"STL/sphereWithHole.stl", ok(F::stl_ascii, 285, 146, false, 9, 0)},
      {"STL/triangle.stl", ok(F::stl_ascii, 1, 3, false, 3, 0)},
      {"STL/triangle_with_empty_solid.stl", ok(F::stl_ascii, 1, 3, false, 3, 0)},
      {"STL/triangle_with_two_solids.stl", ok(F::stl_ascii, 2, 6, false, 6, 0)},
      {"OBJ/WusonOBJ.obj", ok(F::obj, 3732, 2117, false, 412, 0)},
      {"OBJ/box.obj", ok(F::obj, 12, 8, true, 0, 0)},
      // Saved as UTF-16 with its byte order mark: decoded, and said.
      {"OBJ/box_UTF16BE.obj", ok(F::obj, 12, 8, true, 0, 0, "UTF-16 text (big-endian)")},
      // One face of 936 corners, most repeated: 478 triangles are left.
      {"OBJ/box_longline.obj", ok(F::obj, 478, 8, false, 0, 5)},
      {"OBJ/box_mat_with_spaces.obj", ok(F::obj, 12, 8, true, 0, 0)},
      {"OBJ/box_without_lineending.obj", ok(F::obj, 12, 8, true, 0, 0)},
      // A keyhole polygon of 66 corners, fanned from its first corner.
      {"OBJ/concave_polygon.obj", ok(F::obj, 64, 64, false, 63, 2)},
      {"OBJ/cube_mtllib_after_g.obj", ok(F::obj, 12, 8, true, 0, 0)},
      {"OBJ/cube_usemtl.obj", ok(F::obj, 12, 8, true, 0, 0)},
      {"OBJ/cube_with_vertexcolors.obj", ok(F::obj, 12, 8, true, 0, 0)},
      {"OBJ/cube_with_vertexcolors_uni.obj", ok(F::obj, 12, 8, true, 0, 0)},
      {"OBJ/empty_mat.obj", ok(F::obj, 256, 130, true, 0, 0)},
      // Tabs and runs of spaces between the numbers.
      {"OBJ/multiple_spaces.obj", ok(F::obj, 1, 3, false, 3, 0)},
      // "3.1+e2" is no number (assimp reads 3.1 and drops the rest).
      {"OBJ/number_formats.obj", refused(E::malformed_input, "OBJ, line 11: a vertex needs 3 numbers, found '3.1+e2'")},
      {"OBJ/point_cloud.obj", refused(E::no_usable_triangles, "OBJ contains no faces")},
      {"OBJ/regr01.obj", ok(F::obj, 2710, 1271, false, 50, 35)},
      {"OBJ/regr_3429812.obj", ok(F::obj, 4, 4, false, 0, 1)},
      {"OBJ/space_in_material_name.obj", ok(F::obj, 64, 64, false, 63, 2)},
      {"OBJ/spider.obj", ok(F::obj, 1368, 722, false, 72, 0)},
      {"OBJ/testline.obj", refused(E::no_usable_triangles, "OBJ contains no faces")},
      {"OBJ/testmixed.obj", ok(F::obj, 12, 8, true, 0, 0)},
      {"OBJ/testpoints.obj", refused(E::no_usable_triangles, "OBJ contains no faces")},
      // Blender 2.47 wrote "Created by Blender3D 247 ..." as a header line
      // of its own: read as a comment, and said.
      {"PLY/Wuson.ply", ok(F::ply, 3732, 2117, false, 412, 0, "PLY header, line 3: unknown keyword 'Created'")},
      {"PLY/cube.ply", ok(F::ply, 12, 8, true, 0, 0)},
      {"PLY/cube_binary.ply", ok(F::ply, 12, 8, true, 0, 0)},
      {"PLY/cube_uv.ply", ok(F::ply, 12, 8, true, 0, 0)},
      {"PLY/float-color.ply", ok(F::ply, 1, 3, false, 3, 0)},
      // Its header puts the face list in the vertex element.
      {"PLY/issue623.ply", refused(E::malformed_input, "PLY, line 14 (vertex 0 of 24): expected an integer")},
      {"PLY/points.ply", refused(E::no_usable_triangles, "PLY contains no faces")},
      // 69 bytes short of its 70,051 vertices of 31 bytes.
      {"PLY/pond.0.ply", refused(E::truncated_input, "need at least 2171581 bytes of data, but only 2171512")},
      {"invalid/empty.obj", refused(E::empty_input, "the mesh file is empty")},
      {"invalid/empty.ply", refused(E::empty_input, "the mesh file is empty")},
      // Index 0 (OBJ counts from 1), and a face of no corners.
      {"invalid/malformed.obj", refused(E::malformed_input, "OBJ, line 28: face refers to vertex 0")},
      {"invalid/malformed2.obj", refused(E::malformed_input, "OBJ, line 23: a face needs at least 3 vertices")},
  };
  return table;
}

// Every STL, OBJ and PLY file the package installs, and the broken OBJ and
// PLY files of invalid/.
std::vector<std::string> corpus_files() {
  std::vector<std::string> files;
  const std::filesystem::path root = test::assimp_model(".");
  for (const char* folder : {"STL", "OBJ", "PLY", "invalid"}) {
    for (const auto& entry : std::filesystem::directory_iterator(root / folder)) {
      if (!entry.is_regular_file()) continue;
      std::string ext = entry.path().extension().string();
      std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
      const bool mesh = ext == ".stl" || ext == ".obj" || ext == ".ply" || (std::string(folder) == "STL" && ext.empty());
      if (mesh) files.push_back(std::string(folder) + "/" + entry.path().filename().string());
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

TEST(MeshCorpus, EveryFileOfAssimpsCorpusDecodesOrIsRefusedAsExpected) {
  const std::vector<std::string> files = corpus_files();
  EXPECT_EQ(files.size(), corpus().size());
  for (const std::string& file : files) {
    SCOPED_TRACE(file);
    const auto it = corpus().find(file);
    if (it == corpus().end()) {
      ADD_FAILURE() << "no expected outcome for " << file;
      continue;
    }
    const Expected& want = it->second;
    const std::vector<std::uint8_t> bytes = test::read_file(test::assimp_model(file));
    DecodeWarnings warnings;
    try {
      const Mesh mesh = decode_mesh(bytes, file, {}, &warnings);
      ASSERT_TRUE(want.decodes) << "decoded, expected " << want.refused->message;
      const Decodes& d = *want.decodes;
      EXPECT_EQ(detect_mesh_format(bytes, file), d.format);
      const MeshReport r = make_mesh_report(mesh);
      EXPECT_EQ(r.triangles, d.triangles);
      EXPECT_EQ(r.vertices, d.vertices);
      EXPECT_EQ(r.watertight, d.watertight);
      EXPECT_EQ(r.boundary_edges, d.boundary_edges);
      EXPECT_EQ(r.nonmanifold_edges, d.nonmanifold_edges);
      if (d.warning) {
        ASSERT_EQ(warnings.size(), 1u);
        EXPECT_NE(warnings[0].find(d.warning), std::string::npos) << warnings[0];
      } else {
        EXPECT_TRUE(warnings.empty()) << warnings[0];
      }
    } catch (const Error& e) {
      ASSERT_TRUE(want.refused) << "refused: " << e.what();
      EXPECT_EQ(e.code(), want.refused->code) << e.what();
      EXPECT_NE(std::string(e.what()).find(want.refused->message), std::string::npos) << e.what();
    }
  }
}

// Twins of one model in other formats decode to the same triangles: the
// spider in ASCII and binary STL (its OBJ is another scale); Wuson in STL,
// OBJ and PLY.
TEST(MeshCorpus, TwinsInOtherFormatsAreTheSameSurface) {
  const auto report = [](const std::string& file) {
    return make_mesh_report(decode_mesh(test::read_file(test::assimp_model(file)), file));
  };
  for (const std::vector<std::string>& twins :
       {std::vector<std::string>{"STL/Spider_ascii.stl", "STL/Spider_binary.stl"},
        {"STL/Wuson.stl", "OBJ/WusonOBJ.obj", "PLY/Wuson.ply"}}) {
    const MeshReport first = report(twins[0]);
    for (std::size_t i = 1; i < twins.size(); ++i) {
      SCOPED_TRACE(twins[0] + " and " + twins[i]);
      const MeshReport r = report(twins[i]);
      EXPECT_EQ(r.triangles, first.triangles);
      EXPECT_EQ(r.vertices, first.vertices);
      EXPECT_EQ(r.boundary_edges, first.boundary_edges);
      EXPECT_NEAR(r.surface_area, first.surface_area, 1e-5 * first.surface_area);
      for (int a = 0; a < 3; ++a) {
        EXPECT_NEAR(r.bbox.min[a], first.bbox.min[a], 1e-5);
        EXPECT_NEAR(r.bbox.max[a], first.bbox.max[a], 1e-5);
      }
    }
  }
}

// The UTF-16 box is box.obj to the last bit.
TEST(MeshCorpus, Utf16ObjIsItsUtf8Twin) {
  const Mesh utf16 = decode_mesh(test::read_file(test::assimp_model("OBJ/box_UTF16BE.obj")), "box_UTF16BE.obj");
  const Mesh utf8 = decode_mesh(test::read_file(test::assimp_model("OBJ/box.obj")), "box.obj");
  ASSERT_EQ(utf16.vertices.size(), utf8.vertices.size());
  ASSERT_EQ(utf16.triangles.size(), utf8.triangles.size());
  for (std::size_t i = 0; i < utf8.vertices.size(); ++i) EXPECT_EQ(utf16.vertices[i], utf8.vertices[i]) << i;
  for (std::size_t i = 0; i < utf8.triangles.size(); ++i) EXPECT_EQ(utf16.triangles[i], utf8.triangles[i]) << i;
}

// UTF-16 made here: little-endian, with characters past the basic plane in
// a comment (a surrogate pair), then broken ways to write it.
std::vector<std::uint8_t> utf16(const std::u16string& text, bool big_endian) {
  std::vector<std::uint8_t> out = big_endian ? std::vector<std::uint8_t>{0xFE, 0xFF} : std::vector<std::uint8_t>{0xFF, 0xFE};
  for (char16_t c : text) {
    const auto hi = static_cast<std::uint8_t>(c >> 8), lo = static_cast<std::uint8_t>(c & 0xFF);
    out.push_back(big_endian ? hi : lo);
    out.push_back(big_endian ? lo : hi);
  }
  return out;
}

TEST(MeshDecodeUtf16, LittleEndianWithSurrogatesDecodesAndBrokenTextNamesItsByte) {
  const Mesh box = test::make_box({0, 0, 0}, {1, 2, 3});
  std::u16string text = u"# made by \U0001F9CA tools, caf\u00e9\n";
  for (char c : test::to_obj(box)) text.push_back(static_cast<char16_t>(c));
  for (bool big : {false, true}) {
    DecodeWarnings warnings;
    const std::vector<std::uint8_t> bytes = utf16(text, big);
    EXPECT_EQ(detect_mesh_format(bytes), MeshFormat::obj);
    const Mesh mesh = decode_mesh(bytes, "box.obj", {}, &warnings);
    EXPECT_EQ(mesh.triangles.size(), 12u);
    EXPECT_DOUBLE_EQ(test::mesh_volume(mesh), 6.0);
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find(big ? "big-endian" : "little-endian"), std::string::npos) << warnings[0];
  }
  const auto refusal = [](std::vector<std::uint8_t> bytes) {
    try {
      decode_mesh(bytes, "x.obj");
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::malformed_input);
      return std::string(e.what());
    }
    return std::string("decoded");
  };
  std::vector<std::uint8_t> odd = utf16(text, false);
  odd.pop_back();
  EXPECT_NE(refusal(odd).find("an odd number of bytes"), std::string::npos) << refusal(odd);
  // A lone low surrogate right after "# ": byte 6 of the file.
  const std::vector<std::uint8_t> lone = utf16(u"# \xDC00\nv 0 0 0\n", false);
  EXPECT_NE(refusal(lone).find("broken at byte 6: a low surrogate"), std::string::npos) << refusal(lone);
}

TEST(MeshDecodePly, AnUnknownHeaderLineIsReadAsACommentAndSaid) {
  const Mesh box = test::make_box({0, 0, 0}, {1, 2, 3});
  std::string ply = test::to_ascii_ply(box);
  ply.insert(ply.find("element vertex"), "Created by Blender3D 247 - www.blender.org\n");
  DecodeWarnings warnings;
  const Mesh mesh = decode_mesh({reinterpret_cast<const std::uint8_t*>(ply.data()), ply.size()}, "b.ply", {}, &warnings);
  EXPECT_EQ(mesh.triangles.size(), 12u);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("PLY header, line 3: unknown keyword 'Created' read as a comment"), std::string::npos)
      << warnings[0];
  // What is read as a comment cannot stand in for what the header needs.
  std::string no_format = test::to_ascii_ply(box);
  no_format.replace(no_format.find("format ascii 1.0"), 16, "fromat ascii 1.0");
  EXPECT_THROW(decode_mesh({reinterpret_cast<const std::uint8_t*>(no_format.data()), no_format.size()}, "b.ply"), Error);
}

}  // namespace
}  // namespace voxd
