// `voxd analyze` as a real process: analysis.json with exact answers for a
// hollow box, an open mesh said to be open, and the published schema.
#include <filesystem>
#include <cstring>
#include <fstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "support/run_process.h"
#include "support/assimp_models.h"
#include "support/test_meshes.h"
#include "support/test_parts.h"

namespace voxd {
namespace {

using nlohmann::json;

class AnalyzeCli : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = test::make_temp_dir("voxd-analyze"); }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  json analyze(const std::string& mesh, const std::string& flags) {
    const auto r = test::run_process(std::string(VOXD_BINARY) + " analyze " + mesh + " -o " + dir_ + "/out " + flags);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    const std::string path = dir_ + "/out/analysis.json";
    const auto schema = test::run_process("/usr/bin/python3 " + std::string(VOXD_SOURCE_DIR) + "/tests/tools/validate_json.py " +
                                          std::string(VOXD_SOURCE_DIR) + "/proto-schemas/analysis.schema.json " + path);
    EXPECT_EQ(schema.exit_code, 0) << schema.out << schema.err;
    std::ifstream in(path);
    return json::parse(in);
  }
  std::string dir_;
};

TEST_F(AnalyzeCli, HollowBoxHasOnePartOneVoidAndExactMassProperties) {
  const Mesh m = test::concat({test::make_box({1, 1, 1}, {11, 11, 11}), test::flipped(test::make_box({3, 4, 5}, {8, 9, 9}))});
  test::write_file(dir_ + "/hollow.stl", test::to_binary_stl(m));
  const json a = analyze(dir_ + "/hollow.stl", "--voxel-size 1 --origin 0,0,0 --dims 12,12,12");
  EXPECT_EQ(a.at("parts").at("count"), 1);
  EXPECT_EQ(a.at("parts").at("items").at(0).at("voxels"), 900);
  // The images beside it; the z radiograph's total is exact per ray: 10
  // voxels of wall, minus 4 where a ray crosses the cavity.
  for (const char* name : {"radiography-x-min.png", "radiography-y-max.png", "radiography-z-total.png",
                           "radiography-z-max-colour.png", "section-x.png", "section-z.png"})
    EXPECT_TRUE(std::filesystem::exists(dir_ + "/out/" + name)) << name;
  const auto png = test::run_process("/usr/bin/python3 " + std::string(VOXD_SOURCE_DIR) + "/tests/tools/read_png.py " + dir_ +
                                     "/out/radiography-z-total.png");
  ASSERT_EQ(png.exit_code, 0) << png.err;
  const json image = json::parse(png.out);
  EXPECT_EQ(image.at("pixels").at(5 * 12 + 5), 10 - 4);  // (x 5, y 5) crosses the cavity (z 5..8)
  EXPECT_EQ(image.at("pixels").at(2 * 12 + 2), 10);      // (x 2, y 2): wall only
  EXPECT_EQ(image.at("pixels").at(0), 0);
  EXPECT_EQ(a.at("voids").at("count"), 1);
  EXPECT_EQ(a.at("voids").at("total_volume"), 100.0);
  EXPECT_EQ(a.at("voids").at("items").at(0).at("bbox_min"), json::array({3.0, 4.0, 5.0}));
  EXPECT_EQ(a.at("voids").at("items").at(0).at("bbox_max"), json::array({8.0, 9.0, 9.0}));
  const json& mass = a.at("mass_properties");
  EXPECT_TRUE(mass.at("mesh").at("available"));
  EXPECT_NEAR(mass.at("mesh").at("volume").get<double>(), 900.0, 1e-9);
  EXPECT_NEAR(mass.at("voxels").at("volume").get<double>(), 900.0, 1e-9);
  // The voxels are exactly the part here: no difference but rounding.
  EXPECT_LT(std::abs(mass.at("difference").at("volume_relative").get<double>()), 1e-12);
  EXPECT_LT(mass.at("difference").at("inertia_relative").get<double>(), 1e-9);
  // Every filled voxel is peeled exactly once; the outer shell alone is 488.
  std::uint64_t peeled = 0;
  for (const auto& n : a.at("skin").at("layers")) peeled += n.get<std::uint64_t>();
  EXPECT_EQ(peeled, 900u);
  EXPECT_GE(a.at("skin").at("layers").at(0).get<std::uint64_t>(), 488u);
  EXPECT_EQ(a.at("skin").at("max_depth").get<double>(), a.at("skin").at("max_depth_layers").get<double>() * 1.0);
}

// The files the service serves for a job, and the job JSON's analyses, with
// the same bytes as the service's worker would keep (the HTTP tests check the
// routes; here the CLI's own copies must agree with them and with the part).
TEST_F(AnalyzeCli, WritesPreviewsTheThicknessVolumeAndTheRequestedAnalyses) {
  // A plate 4 voxels thick on a unit grid: thickness 4 everywhere.
  test::write_file(dir_ + "/plate.stl", test::to_binary_stl(test::make_box({1, 1, 1}, {19, 19, 5})));
  const std::string params = R"({"grid":{"voxel_size":1,"origin":[0,0,0],"dims":[20,20,6]},
      "analyses":[{"kind":"thickness","format":"raw","unit":"voxels"},{"kind":"preview","view":"-y"},
                  {"kind":"radiography","axis":"z","format":"json"}]})";
  {
    std::ofstream out(dir_ + "/params.json");
    out << params;
  }
  const json a = analyze(dir_ + "/plate.stl", "--params @" + dir_ + "/params.json");
  EXPECT_EQ(a.at("thickness").at("min"), 4.0);
  EXPECT_EQ(a.at("thickness").at("max"), 4.0);
  for (const char* view : {"+x", "-x", "+y", "-y", "+z", "-z"}) {
    for (const char* suffix : {".png", "-thickness.png"}) {
      const std::string file = dir_ + "/out/preview-from" + view + suffix;
      const auto png = test::run_process("/usr/bin/python3 " + std::string(VOXD_SOURCE_DIR) + "/tests/tools/read_png.py " + file + " --checksum");
      ASSERT_EQ(png.exit_code, 0) << file << png.err;
      EXPECT_EQ(json::parse(png.out).at("text").at("voxd:view"), view);
    }
  }
  for (const char* name : {"section-x-thickness.png", "section-y-thickness.png", "section-z-thickness.png"})
    EXPECT_TRUE(std::filesystem::exists(dir_ + "/out/" + name)) << name;
  // thickness.nrrd: model units (= voxels here), 4 inside the plate.
  const auto nrrd = test::read_file(dir_ + "/out/thickness.nrrd");
  const std::string text(nrrd.begin(), nrrd.end());
  const std::size_t data = text.find("\n\n") + 2;
  ASSERT_EQ(nrrd.size() - data, 20u * 20 * 6 * 4);
  float v = 0;
  std::memcpy(&v, nrrd.data() + data + 4 * (10 + 20 * (10 + 20 * 3)), 4);
  EXPECT_EQ(v, 4.0f);
  std::memcpy(&v, nrrd.data() + data, 4);
  EXPECT_EQ(v, 0.0f);
  // The requested analyses, named by their keys: the raw thickness equals
  // the NRRD's data, and the radiography statistics see the 4-voxel plate.
  const auto raw = test::read_file(dir_ + "/out/analyses/thickness_measure-wall__format-raw__unit-voxels.raw");
  EXPECT_EQ(raw, std::vector<std::uint8_t>(nrrd.begin() + static_cast<std::ptrdiff_t>(data), nrrd.end()));
  EXPECT_TRUE(std::filesystem::exists(dir_ + "/out/analyses/preview_view-my__colour-none.png"));
  std::ifstream stats_file(dir_ + "/out/analyses/radiography_axis-z__measure-max__format-json__unit-voxels.json");
  const json stats = json::parse(stats_file);
  EXPECT_EQ(stats.at("max"), 4.0);
  EXPECT_EQ(stats.at("rays"), 18 * 18);
}

TEST_F(AnalyzeCli, AnOpenMeshSaysItIsOpenInsteadOfAVolume) {
  // assimp's sphere of radius 1.5 with a hole of 9 edges in it.
  const json a = analyze(test::assimp_model("STL/sphereWithHole.stl"), "--resolution 48 --inside winding");
  const json& mesh = a.at("mass_properties").at("mesh");
  EXPECT_FALSE(mesh.at("available"));
  EXPECT_NE(mesh.at("reason").get<std::string>().find("not closed"), std::string::npos);
  EXPECT_TRUE(a.at("mass_properties").at("difference").is_null());
  EXPECT_GT(a.at("mass_properties").at("voxels").at("volume").get<double>(), 0.0);
}

TEST_F(AnalyzeCli, CleanupIsReportedAndUsageErrorsExitTwo) {
  test::write_file(dir_ + "/box.stl", test::to_binary_stl(test::make_box({0, 0, 0}, {4, 4, 4})));
  const json a = analyze(dir_ + "/box.stl", "--resolution 8 --cleanup");
  EXPECT_EQ(a.at("cleanup").at("isolated"), 0);
  EXPECT_EQ(a.at("parts").at("count"), 1);
  EXPECT_EQ(test::run_process(std::string(VOXD_BINARY) + " analyze " + dir_ + "/box.stl").exit_code, 2);
  EXPECT_EQ(test::run_process(std::string(VOXD_BINARY) + " analyze " + dir_ + "/box.stl -o " + dir_ + "/o --resolution 0").exit_code, 2);
}

}  // namespace
}  // namespace voxd
