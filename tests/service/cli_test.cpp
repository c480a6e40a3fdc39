// The `voxd` command line, run as a real process.
#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "support/run_process.h"
#include "support/assimp_models.h"
#include "support/test_meshes.h"
#include "support/test_parts.h"
#include "voxd/encode/volume_format.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd {
namespace {

using nlohmann::json;
using test::run_process;

const std::string kVoxd = VOXD_BINARY;

class CliTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = test::make_temp_dir("voxd-cli"); }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string path(const std::string& name) const { return dir_ + "/" + name; }
  std::string write_mesh(const std::string& name, const Mesh& mesh) {
    test::write_file(path(name), test::to_binary_stl(mesh));
    return path(name);
  }
  // Runs `command` with --streaming on and off, each writing `out`: the
  // two files must be equal, the first run streamed and the second not.
  // Returns both summaries (null ones after a fatal failure).
  std::pair<json, json> streamed_and_in_memory(const std::string& command, const std::string& out) {
    const auto on = run_process(command + " --streaming on --json -o " + path("on_" + out));
    const auto off = run_process(command + " --streaming off --json -o " + path("off_" + out));
    [&] {
      ASSERT_EQ(on.exit_code, 0) << on.err;
      ASSERT_EQ(off.exit_code, 0) << off.err;
    }();
    if (HasFatalFailure()) return {};
    EXPECT_EQ(test::read_file(path("on_" + out)), test::read_file(path("off_" + out)));
    json a = json::parse(on.out), b = json::parse(off.out);
    EXPECT_TRUE(a.at("streamed").get<bool>());
    EXPECT_FALSE(b.at("streamed").get<bool>());
    return {std::move(a), std::move(b)};
  }
  std::string dir_;
};

// The file of a part of test_parts.h, written by the build (tests/CMakeLists.txt).
std::string part_file(const std::string& name) {
  const std::string p = std::string(VOXD_TEST_PARTS) + "/" + name;
  if (!std::filesystem::exists(p)) throw std::runtime_error("test part missing (the build writes it): " + p);
  return p;
}

TEST_F(CliTest, InspectPrintsTheMeshReportAsJson) {
  const std::string mesh = write_mesh("box.stl", test::make_box({0, 0, 0}, {2, 3, 4}));
  const auto r = run_process(kVoxd + " inspect " + mesh);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json report = json::parse(r.out);
  EXPECT_EQ(report.at("triangles"), 12);
  EXPECT_EQ(report.at("vertices"), 8);
  EXPECT_EQ(report.at("watertight"), true);
  EXPECT_EQ(report.at("boundary_edges"), 0);
  EXPECT_EQ(report.at("nonmanifold_edges"), 0);
  EXPECT_EQ(report.at("degenerate_triangles"), 0);
  EXPECT_DOUBLE_EQ(report.at("volume").get<double>(), 24.0);
  EXPECT_DOUBLE_EQ(report.at("surface_area").get<double>(), 52.0);
  EXPECT_EQ(report.at("bbox_max"), json::array({2.0, 3.0, 4.0}));
  EXPECT_EQ(report.at("format"), "stl_binary");
}

// Blender's Wuson (assimp-testmodels), open at its seams: 412 edges used
// once, counted apart (mesh_report_test).
TEST_F(CliTest, InspectReportsTheOpenRealWuson) {
  const auto r = run_process(kVoxd + " inspect " + test::assimp_model("STL/Wuson.stl"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json report = json::parse(r.out);
  EXPECT_EQ(report.at("boundary_edges"), 412);
  EXPECT_EQ(report.at("watertight"), false);
  EXPECT_TRUE(report.at("volume").is_null());
}

// A part written inside out: nothing in the edge counts shows it (every
// edge is consistent), the orientation does; and what "auto" would choose.
TEST_F(CliTest, InspectSaysAPartIsInsideOutAndWhichInsideTestAutoChooses) {
  const std::string inverted = write_mesh("inverted.stl", test::flipped(test::make_box({0, 0, 0}, {4, 3, 2})));
  const auto r = run_process(kVoxd + " inspect " + inverted);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json report = json::parse(r.out);
  EXPECT_EQ(report.at("inconsistent_edges"), 0);
  EXPECT_DOUBLE_EQ(report.at("volume").get<double>(), -24.0);  // the file as it is
  EXPECT_EQ(report.at("orientation").at("inverted_components"), 1);
  EXPECT_EQ(report.at("orientation").at("flipped_triangles"), 12);
  EXPECT_EQ(report.at("inside").at("test"), "parity");
  const auto open = run_process(kVoxd + " inspect " + test::assimp_model("STL/Wuson.stl"));
  ASSERT_EQ(open.exit_code, 0) << open.err;
  EXPECT_EQ(json::parse(open.out).at("inside").at("test"), "winding");
}

// The mesh file's unit: a box 4 x 3 x 2 m is voxelized and reported in mm,
// and a voxel of 100 mm makes 40 x 30 x 20 of them; the summary says so.
TEST_F(CliTest, VoxelizeReadsTheMeshInItsUnitAndReportsMillimetres) {
  const std::string box = write_mesh("box_m.stl", test::make_box({0, 0, 0}, {4, 3, 2}));
  const auto r = run_process(kVoxd + " voxelize " + box + " --units m --voxel-size 100 --report -o " + path("m.rle") + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json s = json::parse(r.out);
  EXPECT_EQ(s.at("grid").at("dims"), json::array({40, 30, 20}));
  EXPECT_EQ(s.at("units"), json({{"mesh", "m"}, {"lengths", "mm"}}));
  EXPECT_DOUBLE_EQ(s.at("report").at("volume").get<double>(), 24e9);
  EXPECT_EQ(s.at("filled_voxels"), 40 * 30 * 20);
  const auto bad = run_process(kVoxd + " voxelize " + box + " --units yards -o " + path("y.rle"));
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("/units"), std::string::npos) << bad.err;
  // Without the unit, a part 4 mm across with a 100 mm voxel: both warned on
  // standard error with their codes.
  const auto plain = run_process(kVoxd + " voxelize " + box + " --voxel-size 100 -o " + path("p.rle"));
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  EXPECT_NE(plain.err.find("warning: the voxel (100 mm) is larger than the part (4 mm across)"), std::string::npos) << plain.err;
  EXPECT_NE(plain.err.find("[voxel-larger-than-part]"), std::string::npos) << plain.err;
}

// What decoding noticed comes with the report: Blender 2.47's PLY header
// line, and UTF-16 text (assimp-testmodels); a plain file has no warnings.
TEST_F(CliTest, InspectSaysWhatDecodingNoticed) {
  const auto ply = run_process(kVoxd + " inspect " + test::assimp_model("PLY/Wuson.ply"));
  ASSERT_EQ(ply.exit_code, 0) << ply.err;
  const json p = json::parse(ply.out);
  ASSERT_EQ(p.at("warnings").size(), 1u) << ply.out;
  EXPECT_NE(p.at("warnings")[0].get<std::string>().find("unknown keyword 'Created' read as a comment"), std::string::npos);
  const auto obj = run_process(kVoxd + " inspect " + test::assimp_model("OBJ/box_UTF16BE.obj"));
  ASSERT_EQ(obj.exit_code, 0) << obj.err;
  const json o = json::parse(obj.out);
  EXPECT_EQ(o.at("format"), "obj");
  EXPECT_EQ(o.at("triangles"), 12);
  ASSERT_EQ(o.at("warnings").size(), 1u) << obj.out;
  EXPECT_NE(o.at("warnings")[0].get<std::string>().find("UTF-16"), std::string::npos);
  const auto plain = run_process(kVoxd + " inspect " + test::assimp_model("OBJ/box.obj"));
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  EXPECT_FALSE(json::parse(plain.out).contains("warnings"));
}

TEST_F(CliTest, VoxelizeJsonSummaryMatchesTheEngineAndTheFile) {
  const Mesh sphere = test::make_icosphere({1, 2, 3}, 5.0, 4);
  const std::string mesh = write_mesh("sphere.stl", sphere);
  const auto r = run_process(kVoxd + " voxelize " + mesh + " --resolution 40 --padding 1 -o " + path("s.rle") + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json s = json::parse(r.out);
  EXPECT_EQ(s.at("grid").at("dims"), json::array({42, 42, 42}));
  EXPECT_EQ(s.at("mode"), "solid");
  // A closed sphere: "auto" (the default) chooses parity, and says why.
  EXPECT_EQ(s.at("inside").at("test"), "parity");
  EXPECT_EQ(s.at("inside").at("chosen"), "auto");
  EXPECT_EQ(s.at("warnings"), json::array());
  EXPECT_EQ(s.at("units"), json({{"mesh", "mm"}, {"lengths", "mm"}}));
  // An RLE of bits is made from runs, in one stage; a binvox from the dense
  // volume, voxelized then encoded.
  for (const char* stage : {"parse", "voxelize+write", "total"}) EXPECT_TRUE(s.at("timings").contains(stage)) << stage;
  EXPECT_FALSE(s.at("timings").contains("voxelize"));
  const auto dense = run_process(kVoxd + " voxelize " + mesh + " --resolution 40 --padding 1 -o " + path("s.binvox") + " --json");
  ASSERT_EQ(dense.exit_code, 0) << dense.err;
  const json d = json::parse(dense.out);
  for (const char* stage : {"parse", "voxelize", "encode", "total"}) EXPECT_TRUE(d.at("timings").contains(stage)) << stage;
  EXPECT_EQ(d.at("filled_voxels"), s.at("filled_voxels"));

  const BitVolume from_file = read_rle_bits(test::read_file(path("s.rle")));
  EXPECT_EQ(from_file.count(), s.at("filled_voxels").get<std::uint64_t>());
  const double h = s.at("grid").at("voxel_size").get<double>();
  EXPECT_NEAR(s.at("filled_volume").get<double>(), static_cast<double>(from_file.count()) * h * h * h, 1e-9);
  EXPECT_NEAR(from_file.grid().voxel_size, h, 1e-15);

  // The CLI result equals the library's on the same mesh and grid.
  const BitVolume direct = voxelize(sphere, from_file.grid(), {});
  EXPECT_EQ(direct.count(), from_file.count());
}

// A volume on standard output is alone there: the --json summary goes to
// standard error, and the bytes equal the file the same job writes.
TEST_F(CliTest, StandardOutputHoldsOnlyTheVolumeWithJson) {
  const std::string mesh = write_mesh("box.stl", test::make_box({0, 0, 0}, {2, 3, 4}));
  const auto piped = run_process(kVoxd + " voxelize " + mesh + " -o - --format raw --json --report");
  ASSERT_EQ(piped.exit_code, 0) << piped.err;
  ASSERT_EQ(run_process(kVoxd + " voxelize " + mesh + " -o " + path("box.raw")).exit_code, 0);
  const auto file = test::read_file(path("box.raw"));
  EXPECT_EQ(piped.out, std::string(file.begin(), file.end()));
  const json summary = json::parse(piped.err);
  EXPECT_EQ(summary.at("output").at("path"), "-");
  EXPECT_EQ(summary.at("output").at("bytes").get<std::size_t>(), file.size());
  // The default grid is 128 voxels along the longest axis (z: 4), no padding.
  EXPECT_EQ(summary.at("grid").at("dims"), json::array({64, 96, 128}));
  EXPECT_EQ(file.size(), 64u * 96u * 128u);
}

TEST_F(CliTest, AllFormatsHoldTheSameVoxels) {
  const std::string mesh = write_mesh("torus.stl", test::make_torus({0, 0, 0}, 3, 1, 48, 24));
  ASSERT_EQ(run_process(kVoxd + " voxelize " + mesh + " --resolution 37 -o " + path("t.rle")).exit_code, 0);
  ASSERT_EQ(run_process(kVoxd + " voxelize " + mesh + " --resolution 37 -o " + path("t.binvox")).exit_code, 0);
  ASSERT_EQ(run_process(kVoxd + " voxelize " + mesh + " --resolution 37 -o " + path("t.raw")).exit_code, 0);
  ASSERT_EQ(run_process(kVoxd + " voxelize " + mesh + " --resolution 37 --format raw --raw-packing bits -o " + path("t.bits")).exit_code, 0);
  const BitVolume rle = read_rle_bits(test::read_file(path("t.rle")));
  const BitVolume binvox = read_binvox(test::read_file(path("t.binvox")));
  const BitVolume raw = read_raw(test::read_file(path("t.raw")), rle.grid(), RawPacking::bytes);
  const BitVolume bits = read_raw(test::read_file(path("t.bits")), rle.grid(), RawPacking::bits);
  ASSERT_GT(rle.count(), 100u);
  const auto& d = rle.grid().dims;
  for (std::int64_t k = 0; k < d.z; ++k)
    for (std::int64_t j = 0; j < d.y; ++j)
      for (std::int64_t i = 0; i < d.x; ++i) {
        ASSERT_EQ(rle.get(i, j, k), binvox.get(i, j, k));
        ASSERT_EQ(rle.get(i, j, k), raw.get(i, j, k));
        ASSERT_EQ(rle.get(i, j, k), bits.get(i, j, k));
      }
  EXPECT_EQ(binvox.count(), rle.count());  // the binvox cube padding is empty
}

TEST_F(CliTest, StreamingWritesTheInMemoryBytesSlabBySlab) {
  const std::string mesh = part_file("blob.stl");
  for (const std::string& out : {std::string("v.rle"), std::string("v.raw"), std::string("v.nrrd")}) {
    for (const char* extra : {"", " --raw-packing bits", " --nrrd-encoding gzip"}) {
      if (std::string(extra).find("raw-packing") != std::string::npos && out != "v.raw") continue;
      if (std::string(extra).find("nrrd-encoding") != std::string::npos && out != "v.nrrd") continue;
      SCOPED_TRACE(out + extra);
      const auto [a, b] = streamed_and_in_memory(
          kVoxd + " voxelize " + mesh + " --resolution 150 --mode solid+surface" + extra, out);
      if (HasFatalFailure()) return;
      EXPECT_EQ(a.at("filled_voxels"), b.at("filled_voxels"));
      EXPECT_GT(a.at("filled_voxels").get<std::uint64_t>(), 100000u);
    }
  }
}

TEST_F(CliTest, StreamedCoverageWritesTheInMemoryBytesAndSummary) {
  const std::string mesh = part_file("torus.stl");
  for (const char* coverage : {"{}", "{\"values\":\"f32\"}", "{\"threshold\":0.25}"}) {
    for (const std::string& out : {std::string("c.rle"), std::string("c.raw"), std::string("c.nrrd")}) {
      SCOPED_TRACE(out + " " + coverage);
      const auto [a, b] = streamed_and_in_memory(kVoxd + " voxelize " + mesh +
                                                     " --resolution 70 --params '{\"mode\":\"coverage\",\"coverage\":" +
                                                     coverage + "}'",
                                                 out);
      if (HasFatalFailure()) return;
      EXPECT_EQ(a.at("filled_voxels"), b.at("filled_voxels"));
      EXPECT_GT(a.at("filled_voxels").get<std::uint64_t>(), 10000u);
      EXPECT_EQ(a.at("values"), b.at("values"));  // the covered volume to the last bit, the type, the unit
    }
  }
}

// The band SDF goes slab by slab whenever its output can take slabs (it is
// faster so, whatever the grid): the same bytes, header and summary as in
// memory, for each sign convention and unit.
TEST_F(CliTest, StreamedSdfBandWritesTheInMemoryBytesAndSummary) {
  const std::string mesh = part_file("torus.stl");
  for (const char* sdf : {"{}", "{\"units\":\"voxels\",\"sign_convention\":\"inside_positive\",\"band\":2}"}) {
    for (const std::string& out : {std::string("d.rle"), std::string("d.raw"), std::string("d.nrrd")}) {
      SCOPED_TRACE(out + " " + sdf);
      const auto [a, b] = streamed_and_in_memory(
          kVoxd + " voxelize " + mesh + " --resolution 70 --padding 3 --params '{\"mode\":\"sdf\",\"sdf\":" + sdf + "}'", out);
      if (HasFatalFailure()) return;
      EXPECT_EQ(a.at("filled_voxels"), b.at("filled_voxels"));
      EXPECT_GT(a.at("filled_voxels").get<std::uint64_t>(), 1000u);
      EXPECT_EQ(a.at("values"), b.at("values"));  // min and max to the last bit, unit, convention, band
    }
  }
  const auto automatic = run_process(kVoxd + " voxelize " + mesh + " --resolution 70 --mode sdf --json -o " + path("auto.rle"));
  ASSERT_EQ(automatic.exit_code, 0) << automatic.err;
  EXPECT_TRUE(json::parse(automatic.out).at("streamed").get<bool>());
  const auto quantized = run_process(kVoxd + " voxelize " + mesh + " --resolution 70 --mode sdf --quantize u16 --json -o " +
                                     path("q.rle"));
  ASSERT_EQ(quantized.exit_code, 0) << quantized.err;
  EXPECT_FALSE(json::parse(quantized.out).at("streamed").get<bool>());  // its levels need the whole range
}

TEST_F(CliTest, AutoStreamsFromTheMemoryEstimateNotTheVoxelCount) {
  // 560 x 543 x 432 voxels: 16 MiB of bits stay in memory, while the same
  // grid's coverage (5 bytes a voxel in memory, past 512 MiB) streams.
  const std::string mesh = part_file("blob.stl");
  const auto bits = run_process(kVoxd + " voxelize " + mesh + " --resolution 560 --json -o " + path("b.rle"));
  ASSERT_EQ(bits.exit_code, 0) << bits.err;
  EXPECT_FALSE(nlohmann::json::parse(bits.out).at("streamed").get<bool>());
  const auto coverage = run_process(kVoxd + " voxelize " + mesh +
                                    " --resolution 560 --params '{\"mode\":\"coverage\",\"coverage\":{\"rays\":1}}' --json -o " +
                                    path("c.rle"));
  ASSERT_EQ(coverage.exit_code, 0) << coverage.err;
  const auto summary = nlohmann::json::parse(coverage.out);
  EXPECT_TRUE(summary.at("streamed").get<bool>());
  EXPECT_GT(summary.at("grid").at("dims").at(0).get<std::int64_t>() * summary.at("grid").at("dims").at(1).get<std::int64_t>() *
                summary.at("grid").at("dims").at(2).get<std::int64_t>() * 5,
            std::int64_t{512} << 20);
}

TEST_F(CliTest, StreamingOnSaysWhyAJobCannotStream) {
  const std::string mesh = part_file("torus.stl");
  struct Case {
    std::string flags, says;
  };
  for (const Case& c : {Case{"-o " + path("t.binvox"), "binvox does not stream slab by slab"},
                        Case{"--inside vote -o " + path("t.rle"), "the vote inside test needs the whole grid"},
                        Case{"--params '{\"mode\":\"slice\",\"slice\":{\"function\":\"marble\"}}' -o " + path("t.rle"),
                             "mode slice makes values over the whole grid"},
                        Case{"--params '{\"mode\":\"sdf\",\"sdf\":{\"band\":\"full\"}}' -o " + path("t.rle"),
                             "the full field's nearest-triangle queries need the whole grid"},
                        Case{"--mode sdf --inside winding -o " + path("t.rle"), "the winding inside test needs the whole grid"},
                        Case{"--params '{\"mode\":\"coverage\",\"coverage\":{\"values\":\"f32\"}}' --quantize u8 -o " +
                                 path("t.rle"),
                             "quantized RLE does not stream"},
                        Case{"--streaming maybe -o " + path("t.rle"), "--streaming must be auto, on or off"}}) {
    SCOPED_TRACE(c.flags);
    const std::string streaming = c.flags.find("--streaming") == std::string::npos ? " --streaming on " : " ";
    const auto r = run_process(kVoxd + " voxelize " + mesh + " --resolution 20" + streaming + c.flags);
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find(c.says), std::string::npos) << r.err;
  }
}

TEST_F(CliTest, InMemoryGridsPastTheVoxelLimitPointToStreaming) {
  const std::string mesh = part_file("torus.stl");
  // 8192 x 8192 x ~1700 voxels: past 2^36, refused before any work.
  const auto r = run_process(kVoxd + " voxelize " + mesh + " --resolution 8192 --streaming off -o " + path("t.rle"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("over the limit of 68719476736"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--streaming on"), std::string::npos) << r.err;
  // A limit the user set holds however the job runs.
  const auto mine = run_process(kVoxd + " voxelize " + mesh + " --resolution 64 --streaming on --max-voxels 1000 -o " + path("t.rle"));
  EXPECT_EQ(mine.exit_code, 2);
  EXPECT_NE(mine.err.find("over the limit of 1000"), std::string::npos) << mine.err;
}

TEST_F(CliTest, ParamsFileAndFlagsCombineFlagsWinning) {
  const std::string mesh = write_mesh("box.stl", test::make_box({0, 0, 0}, {10, 10, 10}));
  {
    std::ofstream f(path("job.json"));
    f << R"({"grid": {"voxel_size": 2.0, "origin": [0, 0, 0], "dims": [5, 5, 5]}, "mode": "surface"})";
  }
  auto r = run_process(kVoxd + " voxelize " + mesh + " --params @" + path("job.json") + " -o " + path("a.rle") + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  json s = json::parse(r.out);
  EXPECT_EQ(s.at("grid").at("dims"), json::array({5, 5, 5}));
  EXPECT_EQ(s.at("mode"), "surface");
  r = run_process(kVoxd + " voxelize " + mesh + " --params @" + path("job.json") + " --mode solid --dims 6,5,5 -o " + path("b.rle") + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  s = json::parse(r.out);
  EXPECT_EQ(s.at("grid").at("dims"), json::array({6, 5, 5}));
  EXPECT_EQ(s.at("mode"), "solid");
  EXPECT_EQ(s.at("filled_voxels"), 125);  // centres 1,3,5,7,9 per axis inside [0,10]
}

TEST_F(CliTest, RotationTurnsTheMeshBeforeTheGridIsLaidOut) {
  // A 10 x 2 x 2 bar turned 90 degrees about z lies along y; the report
  // still describes the bar as uploaded.
  const std::string mesh = write_mesh("bar.stl", test::make_box({0, 0, 0}, {10, 2, 2}));
  const auto r = run_process(kVoxd + " voxelize " + mesh +
                             " --params '{\"rotation\": {\"axis\": [0, 0, 1], \"angle_deg\": 90}, \"grid\": {\"voxel_size\": 0.5}}' -o " +
                             path("bar.rle") + " --json --report");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json s = json::parse(r.out);
  EXPECT_EQ(s.at("grid").at("dims"), json::array({4, 20, 4}));
  EXPECT_EQ(s.at("filled_voxels"), 4 * 20 * 4);
  EXPECT_EQ(s.at("report").at("bbox_max"), json::array({10.0, 2.0, 2.0}));
  EXPECT_NEAR(s.at("rotation")[1][0].get<double>(), 1.0, 1e-12);  // x maps to y
}

TEST_F(CliTest, OrientAutoPutsTheSmallestExtentOnX) {
  const std::string mesh = write_mesh("plate.stl", test::make_box({0, 0, 0}, {10, 8, 1}));
  const auto r = run_process(kVoxd + " voxelize " + mesh + " --params '{\"orient\": \"auto\", \"grid\": {\"voxel_size\": 0.5}}' -o " + path("p.rle") + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json s = json::parse(r.out);
  EXPECT_EQ(s.at("grid").at("dims"), json::array({2, 20, 16}));
  EXPECT_EQ(s.at("filled_voxels"), 2 * 20 * 16);
}

TEST_F(CliTest, ErrorsExitNonZeroWithOneLineMessages) {
  const std::string mesh = write_mesh("box.stl", test::make_box({0, 0, 0}, {1, 1, 1}));
  struct Case {
    std::string args;
    int code;
    std::string fragment;
  };
  const Case cases[] = {
      {"voxelize " + path("missing.stl") + " -o " + path("x.rle"), 1, "cannot open"},
      {"voxelize " + mesh + " -o " + path("x.vox3"), 2, "--format"},
      {"voxelize " + mesh, 2, "needs -o"},
      {"voxelize " + mesh + " -o " + path("x.rle") + " --resolution 0", 2, "/grid/resolution"},
      {"voxelize " + mesh + " -o " + path("x.rle") + " --mode fluffy", 2, "/mode"},
      {"voxelize " + mesh + " -o " + path("x.rle") + " --params '{\"grid\": '", 2, "not valid JSON"},
      {"voxelize " + mesh + " -o " + path("x.rle") + " --params '{\"colour\": 1}'", 2, "/colour: unknown field"},
      {"voxelize " + mesh + " -o " + path("x.rle") + " --frobnicate 3", 2, "unknown option --frobnicate"},
      {"voxelize " + mesh + " -o " + path("x.rle") + " --origin 1,2", 2, "--origin expects 3"},
      {"frobnicate", 2, "unknown command"},
      {"voxelize " + mesh + " -o " + path("x.rle") + " --resolution 100 --max-voxels 1000", 2, "over the limit of 1000"},
      {"inspect " + path("empty.stl"), 1, "empty"},
  };
  test::write_file(path("empty.stl"), {});
  for (const auto& c : cases) {
    const auto r = run_process(kVoxd + " " + c.args);
    EXPECT_EQ(r.exit_code, c.code) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find(c.fragment), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  EXPECT_FALSE(std::filesystem::exists(path("x.rle")));
  EXPECT_FALSE(std::filesystem::exists(path("x.rle.partial")));
}

TEST_F(CliTest, ClosedPartsVoxelizeToTheirMeshVolume) {
  for (const char* name : {"blob.stl", "torus.stl", "hex_nut.stl", "disk.stl", "screw.stl", "flanged_bushing.stl"}) {
    const auto inspect = run_process(kVoxd + " inspect " + part_file(name));
    ASSERT_EQ(inspect.exit_code, 0) << inspect.err;
    const json report = json::parse(inspect.out);
    ASSERT_TRUE(report.at("watertight").get<bool>()) << name;
    const double volume = report.at("volume").get<double>();
    const double area = report.at("surface_area").get<double>();
    const auto r = run_process(kVoxd + " voxelize " + part_file(name) + " --resolution 160 -o " + path("m.rle") + " --json");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const json s = json::parse(r.out);
    const double filled = s.at("filled_volume").get<double>();
    const double h = s.at("grid").at("voxel_size").get<double>();
    // Centre sampling can only err in voxels the surface cuts: half a voxel
    // of the surface's area at most. Within 2% where the part is 40 voxels
    // thick or more (not the 0.2 mm disk, nor the 1.2 mm nut: 30 voxels, one
    // layer more is 3%).
    EXPECT_LE(std::abs(filled - volume), 0.5 * area * h) << name;
    const double wall = test::part_named(name).thinnest_wall;  // 0: the blob, thick throughout
    if (wall > 0 && wall < 40 * h) continue;
    EXPECT_NEAR(filled / volume, 1.0, 0.02) << name;
  }
}

TEST_F(CliTest, ValueModesWriteTheirValuesAndSummarizeThem) {
  const Mesh sphere = test::make_icosphere({0, 0, 0}, 1.0, 4);
  const std::string mesh = write_mesh("sphere.stl", sphere);
  // Coverage as binvox version 2: the grey levels add up to the mesh volume.
  auto r = run_process(kVoxd + " voxelize " + mesh + " -o " + path("c.binvox") +
                       " --resolution 48 --padding 1 --mode coverage --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  json summary = json::parse(r.out);
  EXPECT_EQ(summary.at("mode"), "coverage");
  EXPECT_EQ(summary.at("values").at("type"), "u8");
  const double mesh_volume = test::mesh_volume(sphere);
  EXPECT_NEAR(summary.at("values").at("covered_volume").get<double>(), mesh_volume, 1e-3 * mesh_volume);
  const auto binvox = test::read_file(path("c.binvox"));
  const DenseVolume<std::uint8_t> grey = read_binvox_u8(binvox);
  const double h = summary.at("grid").at("voxel_size").get<double>();
  double total = 0;
  for (std::uint8_t b : grey.values()) total += b / 255.0;
  EXPECT_NEAR(total * h * h * h, mesh_volume, 5e-3 * mesh_volume);  // bytes round each voxel by up to 1/510

  // SDF as gzip NRRD: the header says so, and its negatives are the solid.
  r = run_process(kVoxd + " voxelize " + mesh + " -o " + path("d.nrrd") +
                  " --resolution 32 --padding 3 --mode sdf --nrrd-encoding gzip --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  summary = json::parse(r.out);
  EXPECT_EQ(summary.at("values").at("quantity"), "signed distance");
  const auto nrrd = test::read_file(path("d.nrrd"));
  const std::string text(nrrd.begin(), nrrd.end());
  EXPECT_NE(text.find("\nencoding: gzip\n"), std::string::npos);
  EXPECT_NE(text.find("\ntype: float\n"), std::string::npos);
  EXPECT_NE(text.find("\ncontent: signed distance (model units, inside_negative)\n"), std::string::npos);
  r = run_process(kVoxd + " voxelize " + mesh + " -o " + path("d.raw") + " --resolution 32 --padding 3 --mode sdf --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto raw = test::read_file(path("d.raw"));
  ASSERT_EQ(raw.size(), 38u * 38 * 38 * 4);
  std::uint64_t negative = 0;
  for (std::size_t i = 0; i < raw.size(); i += 4) {
    float v;
    std::memcpy(&v, raw.data() + i, 4);
    negative += v < 0;
  }
  EXPECT_EQ(negative, json::parse(r.out).at("filled_voxels").get<std::uint64_t>());

  // Quantized RLE: u16 levels with their offset and scale in the header.
  r = run_process(kVoxd + " voxelize " + mesh + " -o " + path("q.rle") + " --resolution 32 --padding 3 --mode sdf --quantize u16");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto q = test::read_file(path("q.rle"));
  EXPECT_EQ(read_rle_u16(q).values().size(), 38u * 38 * 38);
  EXPECT_EQ(json::parse(read_rle_metadata(q)).at("quantization").at("levels"), 65535);
  r = run_process(kVoxd + " voxelize " + mesh + " -o " + path("q.rle") + " --resolution 32 --quantize u8");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("not to bits"), std::string::npos) << r.err;

  // What cannot hold the values is refused before any work, in one line.
  r = run_process(kVoxd + " voxelize " + mesh + " -o " + path("d.binvox") + " --resolution 32 --mode sdf");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("float32"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(std::filesystem::exists(path("d.binvox")));
  r = run_process(kVoxd + " voxelize " + mesh + " -o " + path("x.nrrd") + " --mode sdf --nrrd-encoding bz2");
  EXPECT_EQ(r.exit_code, 2);
}

TEST_F(CliTest, PaletteAndSliceWriteTheirMeshesAndColours) {
  // A box on voxel boundaries: every voxel is full or empty, so the palette
  // reconstruction encloses exactly the box.
  const std::string mesh = write_mesh("box.stl", test::make_box({1, 1, 1}, {5, 4, 3}));
  const std::string grid = R"("grid":{"voxel_size":1,"origin":[0,0,0],"dims":[6,5,4]})";
  auto r = run_process(kVoxd + " voxelize " + mesh + " --params '{" + grid + R"(,"mode":"palette"}' -o )" + path("b.stl") + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(json::parse(r.out).at("values").at("palette"), "46");
  const auto stl = test::read_file(path("b.stl"));
  std::uint32_t triangles = 0;
  std::memcpy(&triangles, stl.data() + 80, 4);
  EXPECT_EQ(triangles, 2u * (4 * 3 + 4 * 2 + 3 * 2) * 2);  // the box's exposed unit squares, two triangles each
  double volume = 0;
  for (std::uint32_t t = 0; t < triangles; ++t) {
    float f[12];
    std::memcpy(f, stl.data() + 84 + 50 * t, 48);
    volume += (f[3] * (f[7] * f[11] - f[8] * f[10]) - f[4] * (f[6] * f[11] - f[8] * f[9]) + f[5] * (f[6] * f[10] - f[7] * f[9])) / 6;
  }
  EXPECT_NEAR(volume, 24.0, 1e-4);

  // A slice job: the .vox holds one voxel per filled voxel; a palette mesh
  // format is refused for it, in one line.
  const std::string slice = "'{" + grid + R"(,"mode":"slice","slice":{"function":"checker","checker_size":1}}')";
  r = run_process(kVoxd + " voxelize " + mesh + " --params " + slice + " -o " + path("c.vox") + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(json::parse(r.out).at("filled_voxels"), 24);
  const auto vox = test::read_file(path("c.vox"));
  const std::string text(vox.begin(), vox.end());
  const std::size_t xyzi = text.find("XYZI");
  ASSERT_NE(xyzi, std::string::npos);
  std::uint32_t voxels = 0;
  std::memcpy(&voxels, vox.data() + xyzi + 12, 4);
  EXPECT_EQ(voxels, 24u);
  r = run_process(kVoxd + " voxelize " + mesh + " --params " + slice + " -o " + path("c.glb"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("palette job's reconstruction"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace voxd
