// Mesh decoding: every format round-trips generated meshes exactly, format
// detection follows content, and every kind of bad input gives its error code
// and a message that says what is wrong and where.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "support/draco_cli.h"
#include "support/ply_writer.h"
#include "support/test_meshes.h"
#include "voxd/error.h"
#include "voxd/mesh_io/mesh_decode.h"

namespace voxd {
namespace {

using Bytes = std::vector<std::uint8_t>;

Bytes bytes_of(const std::string& text) { return {text.begin(), text.end()}; }

const Mesh& box() {
  static const Mesh m = test::make_box({-1, 0, 2}, {3, 0.5, 4.25});  // 4 x 0.5 x 2.25
  return m;
}
const Mesh& sphere() {
  static const Mesh m = test::make_icosphere({1, 2, 3}, 2.5, 2);
  return m;
}
const Mesh& torus() {
  static const Mesh m = test::make_torus({0, 0, 1}, 3.0, 1.0, 24, 12);
  return m;
}

struct NamedMesh {
  const char* name;
  const Mesh& mesh;
};
std::vector<NamedMesh> generated_meshes() { return {{"box", box()}, {"icosphere", sphere()}, {"torus", torus()}}; }

// Same triangles, corner by corner, bit for bit (soup or indexed alike).
void expect_same_geometry(const Mesh& decoded, const Mesh& original) {
  ASSERT_EQ(decoded.triangles.size(), original.triangles.size());
  for (std::size_t t = 0; t < original.triangles.size(); ++t)
    for (int c = 0; c < 3; ++c) ASSERT_EQ(decoded.corner(t, c), original.corner(t, c)) << "triangle " << t;
  EXPECT_EQ(test::mesh_volume(decoded), test::mesh_volume(original));
}

// Indexed formats also keep the vertex list and the indices.
void expect_same_indexed_mesh(const Mesh& decoded, const Mesh& original) {
  EXPECT_EQ(decoded.vertices, original.vertices);
  EXPECT_EQ(decoded.triangles, original.triangles);
  expect_same_geometry(decoded, original);
}

// Runs `decode` and checks that it throws voxd::Error with `code` and a
// message containing every one of `details`.
void expect_error(const std::function<void()>& decode, ErrorCode code, const std::vector<std::string>& details) {
  try {
    decode();
  } catch (const Error& e) {
    EXPECT_EQ(to_string(e.code()), std::string(to_string(code))) << "message: " << e.what();
    for (const auto& d : details) EXPECT_NE(std::string(e.what()).find(d), std::string::npos)
        << "message lacks '" << d << "': " << e.what();
    return;
  }
  ADD_FAILURE() << "expected voxd::Error " << to_string(code);
}

// ---- round trips --------------------------------------------------------------

TEST(MeshDecode, BinaryStlRoundTripsAsSoup) {
  for (const auto& [name, mesh] : generated_meshes()) {
    SCOPED_TRACE(name);
    const Bytes stl = test::to_binary_stl(mesh);
    EXPECT_EQ(detect_mesh_format(stl), MeshFormat::stl_binary);
    const Mesh decoded = decode_mesh(stl, "model.stl");
    EXPECT_EQ(decoded.vertices.size(), 3 * mesh.triangles.size());
    expect_same_geometry(decoded, mesh);
  }
}

TEST(MeshDecode, AsciiStlRoundTripsAsSoup) {
  for (const auto& [name, mesh] : generated_meshes()) {
    SCOPED_TRACE(name);
    const Bytes stl = bytes_of(test::to_ascii_stl(mesh));
    EXPECT_EQ(detect_mesh_format(stl), MeshFormat::stl_ascii);
    const Mesh decoded = decode_mesh(stl);
    EXPECT_EQ(decoded.vertices.size(), 3 * mesh.triangles.size());
    expect_same_geometry(decoded, mesh);
  }
}

TEST(MeshDecode, ObjRoundTripsIndexed) {
  for (const auto& [name, mesh] : generated_meshes()) {
    SCOPED_TRACE(name);
    const Bytes obj = bytes_of(test::to_obj(mesh));
    EXPECT_EQ(detect_mesh_format(obj), MeshFormat::obj);
    expect_same_indexed_mesh(decode_mesh(obj), mesh);
  }
}

TEST(MeshDecode, PlyRoundTripsIndexedInEveryEncoding) {
  using Encoding = test::PlyOptions::Encoding;
  for (const auto& [name, mesh] : generated_meshes()) {
    for (Encoding encoding : {Encoding::ascii, Encoding::binary_little_endian, Encoding::binary_big_endian}) {
      SCOPED_TRACE(std::string(name) + " encoding " + std::to_string(static_cast<int>(encoding)));
      test::PlyOptions options;
      options.encoding = encoding;
      const Bytes ply = test::to_ply(mesh, options);
      EXPECT_EQ(detect_mesh_format(ply), MeshFormat::ply);
      expect_same_indexed_mesh(decode_mesh(ply), mesh);
    }
  }
  // The project's own serializers too.
  expect_same_indexed_mesh(decode_mesh(bytes_of(test::to_ascii_ply(torus()))), torus());
  expect_same_indexed_mesh(decode_mesh(test::to_binary_ply(torus())), torus());
}

TEST(MeshDecode, PlyWithDoublesExtraPropertiesAndQuads) {
  using Encoding = test::PlyOptions::Encoding;
  for (Encoding encoding : {Encoding::ascii, Encoding::binary_little_endian, Encoding::binary_big_endian}) {
    SCOPED_TRACE(static_cast<int>(encoding));
    test::PlyOptions options;
    options.encoding = encoding;
    options.coordinate_type = "double";
    options.count_type = "ushort";
    options.index_type = "uint";
    options.index_name = "vertex_index";
    options.extra_properties = true;
    options.quads = true;
    const Bytes ply = test::to_ply(torus(), options);
    // Quads are fan-triangulated back into the same triangles.
    expect_same_indexed_mesh(decode_mesh(ply), torus());
  }
}

TEST(MeshDecode, PlyWithIntegerTypes) {
  const Mesh integer_box = test::make_box({-2, 0, 1}, {5, 3, 4});
  test::PlyOptions options;
  options.encoding = test::PlyOptions::Encoding::binary_big_endian;
  options.coordinate_type = "short";
  options.count_type = "char";
  options.index_type = "ushort";
  const Mesh decoded = decode_mesh(test::to_ply(integer_box, options));
  expect_same_indexed_mesh(decoded, integer_box);
  EXPECT_EQ(test::mesh_volume(decoded), 7.0 * 3.0 * 3.0);
}

TEST(MeshDecode, BinaryStlWhoseHeaderSaysSolidIsBinary) {
  Bytes stl = test::to_binary_stl(box(), "solid box exported by a CAD tool");
  ASSERT_EQ(std::memcmp(stl.data(), "solid", 5), 0);
  EXPECT_EQ(detect_mesh_format(stl), MeshFormat::stl_binary);
  expect_same_geometry(decode_mesh(stl, "box.stl"), box());
  // Trailing bytes after the last record (some exporters pad) are fine, even
  // with the misleading header: the content is still binary.
  stl.insert(stl.end(), {0, 0, 0, 0, 0, 0, 0});
  EXPECT_EQ(detect_mesh_format(stl), MeshFormat::stl_binary);
  expect_same_geometry(decode_mesh(stl), box());
}

TEST(MeshDecode, AsciiStlAsExportersWriteIt) {
  // Upper case, CRLF line ends, tokens split across lines, no normal values,
  // two solids, and no final endsolid.
  const std::string stl =
      "SOLID part one\r\n"
      "FACET NORMAL 0 0 -1\r\n OUTER LOOP\r\n  VERTEX 0 0 0\r\n  VERTEX 0 1 0\r\n  VERTEX 1 0 0\r\n ENDLOOP\r\nENDFACET\r\n"
      "ENDSOLID part one\r\n"
      "solid two\n"
      "facet normal\nouter loop vertex 0 0 0 vertex 1 0 0\nvertex 0 0 1 endloop endfacet\n";
  const Mesh decoded = decode_mesh(bytes_of(stl));
  ASSERT_EQ(decoded.triangles.size(), 2u);
  EXPECT_EQ(decoded.corner(0, 1), glm::vec3(0, 1, 0));
  EXPECT_EQ(decoded.corner(1, 2), glm::vec3(0, 0, 1));
}

TEST(MeshDecode, ObjWithQuadsNegativeIndicesAndTextureNormalRefs) {
  // The box as 6 quads in three index styles, with statements to ignore.
  const std::string obj =
      "# exported\nmtllib box.mtl\no Box\n"
      "v 0 0 0\nv 2 0 0\nv 0 3 0\nv 2 3 0\nv 0 0 4\nv 2 0 4\nv 0 3 4\nv 2 3 4 1.0\n"
      "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\ng side\nusemtl red\ns off\n"
      "f 1/1/1 3/2/1 4/3/1 2/4/1\n"
      "f -4//1 -3//1 -1//1 -2//1\n"           // 5 6 8 7
      "f 1/1 2/2 6/3 5/4\n"
      "f 3 7 8 4\n"
      "f -8/1/1 -4/2/1 -2/3/1 -6/4/1\n"       // 1 5 7 3
      "f 2 4 8 6\n"
      "l 1 2\n";
  const Mesh decoded = decode_mesh(bytes_of(obj));
  EXPECT_EQ(decoded.vertices.size(), 8u);
  EXPECT_EQ(decoded.triangles.size(), 12u);
  EXPECT_EQ(test::mesh_volume(decoded), 24.0);
  // Fan triangulation of "f 3 7 8 4": (3,7,8) and (3,8,4), 0-based.
  EXPECT_EQ(decoded.triangles[6], (std::array<std::uint32_t, 3>{2, 6, 7}));
  EXPECT_EQ(decoded.triangles[7], (std::array<std::uint32_t, 3>{2, 7, 3}));
}

TEST(MeshDecode, ObjPolygonIsFanTriangulated) {
  const std::string obj = "v 0 0 0\nv 1 0 0\nv 2 1 0\nv 1 2 0\nv 0 1 0\nf 1 2 3 4 5\n";
  const Mesh decoded = decode_mesh(bytes_of(obj));
  ASSERT_EQ(decoded.triangles.size(), 3u);
  EXPECT_EQ(decoded.triangles[2], (std::array<std::uint32_t, 3>{0, 3, 4}));
}

TEST(MeshDecode, NumbersOutsideFloatRange) {
  // Too small for float is zero, however it is written; too large is not finite.
  const std::string tiny = "0." + std::string(60, '0') + "1";
  const Mesh decoded = decode_mesh(bytes_of("v 1e-50 +2 0\nv " + tiny + " 0 -1e-400\nv 0 1 0\nf 1 2 3\n"));
  EXPECT_EQ(decoded.vertices[0], glm::vec3(0, 2, 0));
  EXPECT_EQ(decoded.vertices[1], glm::vec3(0, 0, 0));
  expect_error([] { decode_mesh(bytes_of("v 0 0 0\nv 1 0 0\nv 0 1 -1e400\nf 1 2 3\n")); },
               ErrorCode::non_finite_coordinates, {"line 3"});
  expect_error([] { decode_mesh(bytes_of("v 0 0 0\nv 1 0 0\nv 0 1 " + std::string(400, '9') + "\nf 1 2 3\n")); },
               ErrorCode::non_finite_coordinates, {"line 3"});
}

TEST(MeshDecode, ObjForwardReferencesAreResolved) {
  const Mesh decoded = decode_mesh(bytes_of("f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n"), "late.obj");
  EXPECT_EQ(decoded.triangles.size(), 1u);
}

TEST(MeshDecode, RepeatedIndicesAreDroppedButDegenerateGeometryIsKept) {
  // Triangle 2 repeats an index (unusable); triangle 3 is a sliver through
  // three distinct collinear vertices, which the report counts instead.
  const std::string obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 1 2\nf 1 2 4\n";
  const Mesh decoded = decode_mesh(bytes_of(obj));
  ASSERT_EQ(decoded.triangles.size(), 2u);
  EXPECT_EQ(decoded.triangles[1], (std::array<std::uint32_t, 3>{0, 1, 3}));
}

TEST(MeshDecode, DracoFromTheIndependentEncoder) {
  if (!test::draco_encoder_available()) GTEST_SKIP() << test::kDracoEncoder << " is not installed (Debian package draco)";
  for (const auto& [name, mesh] : generated_meshes()) {
    SCOPED_TRACE(name);
    // 24-bit positions keep ~7 digits (at 30 bits draco_encoder takes seconds).
    const Bytes drc = test::encode_with_draco_encoder(mesh, "-qp 24");
    EXPECT_EQ(detect_mesh_format(drc), MeshFormat::draco);
    const Mesh decoded = decode_mesh(drc, "model.drc");
    EXPECT_EQ(decoded.triangles.size(), mesh.triangles.size());
    EXPECT_EQ(decoded.vertices.size(), mesh.vertices.size());
    const double volume = test::mesh_volume(mesh);
    EXPECT_NEAR(test::mesh_volume(decoded), volume, 1e-5 * std::abs(volume));
    const Aabb expected = bounds(mesh), got = bounds(decoded);
    for (int a = 0; a < 3; ++a) {
      EXPECT_NEAR(got.min[a], expected.min[a], 1e-5);
      EXPECT_NEAR(got.max[a], expected.max[a], 1e-5);
    }
  }
  // The default quantization (11 bits) moves vertices by up to ~1/4000 of the size.
  const Bytes coarse = test::encode_with_draco_encoder(torus(), "");
  const double volume = test::mesh_volume(torus());
  EXPECT_NEAR(test::mesh_volume(decode_mesh(coarse)), volume, 2e-3 * volume);
}

TEST(MeshDecode, DracoPointCloudIsRejected) {
  if (!test::draco_encoder_available()) GTEST_SKIP() << test::kDracoEncoder << " is not installed (Debian package draco)";
  const Bytes drc = test::encode_with_draco_encoder(sphere(), "-point_cloud");
  expect_error([&] { decode_mesh(drc, "cloud.drc"); }, ErrorCode::no_usable_triangles, {"point cloud"});
}

TEST(MeshDecode, ToStringNamesEveryFormat) {
  EXPECT_STREQ(to_string(MeshFormat::unknown), "unknown");
  EXPECT_STREQ(to_string(MeshFormat::stl_binary), "stl_binary");
  EXPECT_STREQ(to_string(MeshFormat::stl_ascii), "stl_ascii");
  EXPECT_STREQ(to_string(MeshFormat::obj), "obj");
  EXPECT_STREQ(to_string(MeshFormat::ply), "ply");
  EXPECT_STREQ(to_string(MeshFormat::draco), "draco");
}

TEST(MeshDecode, NameHintOnlyBreaksTies) {
  // Content wins over a misleading name...
  EXPECT_EQ(detect_mesh_format(test::to_binary_stl(box()), "box.obj"), MeshFormat::stl_binary);
  EXPECT_EQ(detect_mesh_format(bytes_of(test::to_obj(box())), "box.stl"), MeshFormat::obj);
  // ...and decides when the content could be OBJ but shows no geometry yet.
  const Bytes comments_first = bytes_of(std::string(70'000, '#') + "\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  EXPECT_EQ(detect_mesh_format(comments_first, "part.OBJ"), MeshFormat::obj);
  EXPECT_EQ(detect_mesh_format(comments_first, "part.bin"), MeshFormat::unknown);
  EXPECT_EQ(decode_mesh(comments_first, "part.obj").triangles.size(), 1u);
}

// ---- bad input ----------------------------------------------------------------

TEST(MeshDecodeErrors, EmptyInput) {
  expect_error([] { decode_mesh({}, "a.stl"); }, ErrorCode::empty_input, {"empty"});
  for (MeshFormat f : {MeshFormat::stl_binary, MeshFormat::stl_ascii, MeshFormat::obj, MeshFormat::ply, MeshFormat::draco})
    expect_error([f] { decode_mesh_as(f, {}); }, ErrorCode::empty_input, {"0 bytes"});
}

TEST(MeshDecodeErrors, TruncatedBinaryStl) {
  Bytes stl = test::to_binary_stl(box());
  stl.resize(84 + 50 * 5 + 20);
  expect_error([&] { decode_mesh(stl, "box.stl"); }, ErrorCode::truncated_input,
               {"declares 12 triangles", "only 354 bytes", "room for 5 triangles"});
  stl.resize(60);
  expect_error([&] { decode_mesh_as(MeshFormat::stl_binary, stl); }, ErrorCode::truncated_input, {"84-byte header"});
  // A count no file could back is caught before anything is allocated.
  Bytes huge = test::to_binary_stl(box());
  const std::uint32_t count = 0xFFFFFFFFu;
  std::memcpy(huge.data() + 80, &count, 4);
  expect_error([&] { decode_mesh(huge); }, ErrorCode::truncated_input, {"declares 4294967295 triangles"});
}

TEST(MeshDecodeErrors, BinaryStlWithoutTriangles) {
  const Bytes stl = test::to_binary_stl(Mesh{});
  expect_error([&] { decode_mesh(stl); }, ErrorCode::no_usable_triangles, {"0 triangles"});
}

TEST(MeshDecodeErrors, AsciiStlMalformedVertexNamesLine) {
  std::string stl = test::to_ascii_stl(box());
  // Line 5 is the second vertex of the first facet.
  const std::size_t at = stl.find("vertex", stl.find("vertex") + 1);
  stl.replace(at, 6, "vertex 1 2 abc #");
  expect_error([&] { decode_mesh(bytes_of(stl)); }, ErrorCode::malformed_input, {"line 5", "'abc'", "coordinate z"});
}

TEST(MeshDecodeErrors, AsciiStlMalformedKeywordNamesLine) {
  std::string stl = test::to_ascii_stl(box());
  stl.replace(stl.find("outer loop"), 10, "outer lop");
  expect_error([&] { decode_mesh(bytes_of(stl)); }, ErrorCode::malformed_input, {"line 3", "'loop'", "'lop'"});

  const std::string misspelled = "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
                                 "endloop\nendfacet\nfacett normal 0 0 1\n";
  expect_error([&] { decode_mesh(bytes_of(misspelled)); }, ErrorCode::malformed_input, {"line 9", "'facett'"});
}

TEST(MeshDecodeErrors, AsciiStlFacetShapes) {
  const std::string four = "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
                           "vertex 1 1 0\nendloop\nendfacet\nendsolid\n";
  expect_error([&] { decode_mesh(bytes_of(four)); }, ErrorCode::malformed_input,
               {"line 7", "starting at line 2", "more than 3 vertices"});
  const std::string two = "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\nendfacet\n";
  expect_error([&] { decode_mesh(bytes_of(two)); }, ErrorCode::malformed_input, {"has 2 vertices"});
  const std::string cut = "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0";
  expect_error([&] { decode_mesh(bytes_of(cut)); }, ErrorCode::truncated_input, {"starting at line 2", "cut off"});
  expect_error([] { decode_mesh(bytes_of("solid empty\nendsolid empty\n")); }, ErrorCode::no_usable_triangles,
               {"no facets"});
}

TEST(MeshDecodeErrors, NonFiniteCoordinates) {
  Bytes stl = test::to_binary_stl(box());
  const float nan = std::nanf("");
  std::memcpy(stl.data() + 84 + 50 * 7 + 12 + 4 * 4, &nan, 4);  // triangle 7, corner 1, y
  expect_error([&] { decode_mesh(stl); }, ErrorCode::non_finite_coordinates, {"triangle 7", "byte offset 434"});

  std::string ascii = test::to_ascii_stl(box());
  ascii.replace(ascii.find("vertex") + 7, 0, "inf ");
  ascii.replace(ascii.find("inf ") + 4, ascii.find('\n', ascii.find("inf ")) - ascii.find("inf ") - 4, "0 0");
  expect_error([&] { decode_mesh(bytes_of(ascii)); }, ErrorCode::non_finite_coordinates, {"line 4"});

  expect_error([] { decode_mesh(bytes_of("v 0 0 0\nv 1e39 0 0\nv 0 1 0\nf 1 2 3\n")); },
               ErrorCode::non_finite_coordinates, {"OBJ", "line 2"});
  expect_error([] { decode_mesh(bytes_of("v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n")); },
               ErrorCode::non_finite_coordinates, {"line 3"});

  Mesh bad = box();
  bad.vertices[3].z = -INFINITY;
  expect_error([&] { decode_mesh(bytes_of(test::to_ascii_ply(bad))); }, ErrorCode::non_finite_coordinates,
               {"PLY", "vertex 3"});
  // A double beyond float range cannot be represented either.
  test::PlyOptions doubles;
  doubles.encoding = test::PlyOptions::Encoding::binary_little_endian;
  doubles.coordinate_type = "double";
  Bytes ply = test::to_ply(box(), doubles);
  const double too_big = 1e300;
  const std::size_t data_start = std::string(ply.begin(), ply.end()).find("end_header\n") + 11;
  std::memcpy(ply.data() + data_start + 5 * 24 + 8, &too_big, 8);  // vertex 5, y
  expect_error([&] { decode_mesh(ply); }, ErrorCode::non_finite_coordinates, {"vertex 5"});
}

TEST(MeshDecodeErrors, NoUsableTriangles) {
  expect_error([] { decode_mesh(bytes_of("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 1 2\nf 3 3 3\n")); },
               ErrorCode::no_usable_triangles, {"2 faces", "repeats a vertex index"});
  expect_error([] { decode_mesh(bytes_of("v 0 0 0\nv 1 0 0\nv 0 1 0\n"), "points.obj"); },
               ErrorCode::no_usable_triangles, {"no faces"});
  const std::string point_cloud = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
                                  "property float z\nend_header\n0 0 0\n1 1 1\n";
  expect_error([&] { decode_mesh(bytes_of(point_cloud)); }, ErrorCode::no_usable_triangles, {"PLY", "no faces"});
}

TEST(MeshDecodeErrors, UnknownFormatListsSupportedOnes) {
  expect_error([] { decode_mesh(bytes_of("hello world\nthis is not a mesh\n"), "notes.txt"); },
               ErrorCode::unknown_format,
               {"'notes.txt'", "'hello world", "binary STL", "ASCII STL", "OBJ", "PLY", "Draco"});
  const Bytes junk = {0x01, 0x02, 'a', 0xfe};
  expect_error([&] { decode_mesh(junk); }, ErrorCode::unknown_format, {"'\\x01\\x02a\\xfe'", "supported formats"});
  expect_error([&] { decode_mesh_as(MeshFormat::unknown, junk); }, ErrorCode::unknown_format, {"supported formats"});
  // Well-known other formats are named, even when long enough to pass for a
  // (broken) binary STL.
  Bytes zip(400, 0);
  std::memcpy(zip.data(), "PK\x03\x04", 4);
  EXPECT_EQ(detect_mesh_format(zip, "part.3mf"), MeshFormat::unknown);
  expect_error([&] { decode_mesh(zip, "part.3mf"); }, ErrorCode::unknown_format, {"'part.3mf'", "ZIP archive", "3MF"});
  const Bytes png = {0x89, 'P', 'N', 'G', 0x0d, 0x0a, 0x1a, 0x0a, 0, 0, 0, 13};
  expect_error([&] { decode_mesh(png); }, ErrorCode::unknown_format, {"PNG image", "supported formats"});
}

TEST(MeshDecodeErrors, ByteLimitIsCheckedBeforeParsing) {
  DecodeLimits limits;
  limits.max_bytes = 100;
  const Bytes stl = test::to_binary_stl(box());
  expect_error([&] { decode_mesh(stl, "", limits); }, ErrorCode::limit_exceeded, {"684 bytes", "limit of 100 bytes"});
  // Checked before the content is looked at at all.
  expect_error([&] { decode_mesh(Bytes(101, 0xAB), "", limits); }, ErrorCode::limit_exceeded, {"101 bytes"});
  expect_error([&] { decode_mesh_as(MeshFormat::obj, Bytes(101, 'x'), limits); }, ErrorCode::limit_exceeded, {});
}

TEST(MeshDecodeErrors, TriangleLimitInEveryFormat) {
  DecodeLimits limits;
  limits.max_triangles = 10;
  const std::vector<std::string> details = {"at least", "limit of 10"};
  expect_error([&] { decode_mesh(test::to_binary_stl(box()), "", limits); }, ErrorCode::limit_exceeded,
               {"binary STL has at least 12 triangles", "limit of 10"});
  expect_error([&] { decode_mesh(bytes_of(test::to_ascii_stl(box())), "", limits); }, ErrorCode::limit_exceeded,
               details);
  expect_error([&] { decode_mesh(bytes_of(test::to_obj(box())), "", limits); }, ErrorCode::limit_exceeded, details);
  expect_error([&] { decode_mesh(test::to_binary_ply(box()), "", limits); }, ErrorCode::limit_exceeded,
               {"PLY has at least 12 triangles"});
  if (test::draco_encoder_available())
    expect_error([&] { decode_mesh(test::encode_with_draco_encoder(box(), ""), "", limits); },
                 ErrorCode::limit_exceeded, {"Draco has at least 12 triangles"});
}

TEST(MeshDecodeErrors, PlyHeaderCountsTheDataCannotBack) {
  // 4e9 vertices in a 100-odd byte file: fails from the header, without
  // trying to reserve 48 GB.
  const std::string huge_vertices = "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\n"
                                    "property float x\nproperty float y\nproperty float z\nend_header\n0123456789";
  expect_error([&] { decode_mesh(bytes_of(huge_vertices)); }, ErrorCode::truncated_input,
               {"4000000000 vertex", "48000000000 bytes", "only 10 bytes"});
  const std::string huge_ascii = "ply\nformat ascii 1.0\nelement vertex 4000000000\n"
                                 "property float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n";
  expect_error([&] { decode_mesh(bytes_of(huge_ascii)); }, ErrorCode::truncated_input, {"4000000000 vertex"});
  const std::string too_many_vertices = "ply\nformat ascii 1.0\nelement vertex 9000000000\n"
                                        "property float x\nproperty float y\nproperty float z\nend_header\n";
  expect_error([&] { decode_mesh(bytes_of(too_many_vertices)); }, ErrorCode::limit_exceeded, {"9000000000 vertices"});
  const std::string too_many_faces = "ply\nformat binary_little_endian 1.0\nelement vertex 3\n"
                                     "property float x\nproperty float y\nproperty float z\nelement face 3000000000\n"
                                     "property list uchar int vertex_indices\nend_header\n";
  expect_error([&] { decode_mesh(bytes_of(too_many_faces)); }, ErrorCode::limit_exceeded,
               {"3000000000 triangles", "limit of 50000000"});
}

TEST(MeshDecodeErrors, TruncatedPlyData) {
  // The header promises more than the file holds.
  Bytes binary = test::to_binary_ply(box());
  binary.resize(binary.size() - 3);
  expect_error([&] { decode_mesh(binary); }, ErrorCode::truncated_input, {"bytes follow the header"});
  // ASCII elements can be shorter than the bound, so the reader notices.
  std::string ascii = test::to_ascii_ply(box());
  ascii.resize(ascii.size() - 12);
  expect_error([&] { decode_mesh(bytes_of(ascii)); }, ErrorCode::truncated_input, {"inside face 10 of 12", "line 28"});
  // A face list longer than the data.
  test::PlyOptions options;
  options.encoding = test::PlyOptions::Encoding::binary_little_endian;
  options.extra_properties = true;
  Bytes ply = test::to_ply(box(), options);
  ply[ply.size() - 4 - 12 - 1 - 8 - 1] = 200;  // the last face's texcoord list length
  expect_error([&] { decode_mesh(ply); }, ErrorCode::truncated_input, {"inside face 11 of 12"});
}

TEST(MeshDecodeErrors, PlyMalformedHeaderAndIndices) {
  const std::string ok_tail = "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                              "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                              "0.0 0.0 0.0\n1.0 0.0 0.0\n0.0 1.0 0.0\n";
  expect_error([&] { decode_mesh(bytes_of("ply\nformat binary_middle_endian 1.0\n" + ok_tail)); },
               ErrorCode::malformed_input, {"line 2", "'binary_middle_endian'"});
  expect_error([&] { decode_mesh(bytes_of("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n")); },
               ErrorCode::malformed_input, {"end_header"});
  expect_error([&] { decode_mesh(bytes_of("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                                          "property float y\nproperty flaot z\nend_header\n")); },
               ErrorCode::malformed_input, {"line 6", "'flaot'"});
  expect_error([&] { decode_mesh(bytes_of("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                                          "property float y\nend_header\n0 0\n")); },
               ErrorCode::malformed_input, {"no 'z' property"});
  expect_error([&] { decode_mesh(bytes_of("ply\nformat ascii 1.0\n" + ok_tail + "3 0 1 3\n")); },
               ErrorCode::malformed_input, {"face 0 of 1", "line 13", "vertex 3", "3 vertices"});
  expect_error([&] { decode_mesh(bytes_of("ply\nformat ascii 1.0\n" + ok_tail + "3 0 -1 2\n")); },
               ErrorCode::malformed_input, {"vertex -1"});
  expect_error([&] { decode_mesh(bytes_of("ply\nformat ascii 1.0\n" + ok_tail + "2 0 1\n")); },
               ErrorCode::malformed_input, {"at least 3 vertices", "has 2"});
  expect_error([&] { decode_mesh(bytes_of("ply\nformat ascii 1.0\n" + ok_tail + "3 0 1 x\n")); },
               ErrorCode::malformed_input, {"line 13", "expected an integer", "'x'"});

  test::PlyOptions options;
  options.encoding = test::PlyOptions::Encoding::binary_big_endian;
  Mesh bad = box();
  bad.triangles[4][2] = 8;
  expect_error([&] { decode_mesh(test::to_ply(bad, options)); }, ErrorCode::malformed_input,
               {"face 4 of 12", "byte offset", "vertex 8", "8 vertices"});
}

TEST(MeshDecodeErrors, ObjIndicesOutOfRange) {
  const std::string v = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  expect_error([&] { decode_mesh(bytes_of(v + "f 1 2 3\nf 1 2 9\n")); }, ErrorCode::malformed_input,
               {"line 5", "vertex 9", "only 3 vertices"});
  expect_error([&] { decode_mesh(bytes_of(v + "f -1 -2 -4\n")); }, ErrorCode::malformed_input,
               {"line 4", "vertex -4", "only 3 vertices"});
  expect_error([&] { decode_mesh(bytes_of(v + "f 0 1 2\n")); }, ErrorCode::malformed_input,
               {"line 4", "vertex 0", "start at 1"});
  expect_error([&] { decode_mesh(bytes_of(v + "f 1 2\n")); }, ErrorCode::malformed_input, {"line 4", "at least 3"});
  expect_error([&] { decode_mesh(bytes_of(v + "f 1 2 three\n")); }, ErrorCode::malformed_input, {"line 4", "'three'"});
  expect_error([&] { decode_mesh(bytes_of("v 0 0\n" + v + "f 1 2 3\n")); }, ErrorCode::malformed_input,
               {"line 1", "3 numbers"});
  expect_error([&] { decode_mesh(bytes_of("v 0,5 0 0\n" + v + "f 1 2 3\n")); }, ErrorCode::malformed_input,
               {"line 1", "'0,5'"});
}

TEST(MeshDecodeErrors, WrongFormatForcedOnData) {
  expect_error([] { decode_mesh_as(MeshFormat::ply, bytes_of(test::to_obj(box()))); }, ErrorCode::malformed_input,
               {"start with 'ply'"});
  expect_error([] { decode_mesh_as(MeshFormat::stl_ascii, bytes_of(test::to_obj(box()))); },
               ErrorCode::malformed_input, {"line 1", "expected 'solid'", "'#'"});
  Bytes not_draco = bytes_of("DRACO garbage that is not a draco stream at all");
  expect_error([&] { decode_mesh(not_draco); }, ErrorCode::malformed_input, {"Draco"});
}

// Inputs the fuzzers found (tests/fuzz/regressions), decoded in process as
// the CLI does: each is refused with an Error before the decoder allocates
// what its header claims (the first made libdraco reserve 5.7 GB).
TEST(MeshDecode, FuzzFindingsAreRefused) {
  const std::filesystem::path dir = std::filesystem::path(VOXD_SOURCE_DIR) / "tests/fuzz/regressions";
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    std::ifstream in(entry.path(), std::ios::binary);
    const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    DecodeLimits limits;
    limits.max_triangles = 1'000'000;
    // Called only once the Draco header's counts have passed their checks:
    // these files must be refused before libdraco sees them.
    limits.draco_decoder = [&](std::span<const std::uint8_t>) -> Mesh {
      ADD_FAILURE() << entry.path() << " reached libdraco";
      throw Error(ErrorCode::malformed_input, "stopped by the test");
    };
    EXPECT_THROW(decode_mesh(bytes, entry.path().filename().string(), limits), Error) << entry.path();
    ++files;
  }
  EXPECT_GE(files, 1);
}

}  // namespace
}  // namespace voxd
