// Liao's interaction through the real `voxd serve`: a finished solid job's
// sections and previews coloured by a slice function given in the request
// (colour=slice), as an editor asks for them while a parameter is dragged.
// Each must show the pixels the slice job of the same upload and function
// then makes, the key its result is kept under must be the function's
// (however the JSON is spelled), and bad functions get clear refusals.
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "support/http_fixture.h"
#include "support/test_meshes.h"
#include "voxd/transform.h"

namespace voxd::test {
namespace {

using nlohmann::json;
using SliceEditingTest = HttpServiceTest;

std::string escaped(const std::string& text) { return httplib::detail::encode_query_param(text); }

// A torus turned off the axes, so the frame's extent is not the grid's box.
Mesh part() {
  Mesh m = make_torus({0.1, -0.2, 0.05}, 1.0, 0.4, 40, 20);
  rotate_mesh(m, rotation_from_axis_angle({1.0, 0.3, 0.2}, 33.0));
  return m;
}

// The job's upload settings: a grid of odd sizes, and a rotation the job
// applies before voxelizing (the kept mesh must be turned the same way).
const std::string kGrid = R"("grid":{"resolution":45,"padding":1},"rotation":{"axis":[0.2,1,0.4],"angle_deg":21})";

TEST_F(SliceEditingTest, ASolidsSlicedSectionsAndPreviewsAreTheSliceJobsOwnPixels) {
  start();
  const std::vector<std::uint8_t> stl = to_binary_stl(part());
  const std::string solid = finished(submit(stl, "{" + kGrid + "}"));
  const json grid = expect_json(http().Get(("/v1/jobs/" + solid).c_str()), 200, "JobStatus").at("grid");
  const std::vector<std::string> functions = {
      R"({"function":"marble","axis":[0.3,-0.5,1],"period":0.7,"turbulence":1.3,"noise_scale":0.3,"octaves":3,"seed":7})",
      R"({"function":"wood","period":0.25,"noise_colors":["#402000",[200,150,90],"#f0e0c0c0"]})",
      R"({"function":"color_ramp","axis":[1,1,0],"ramp":[{"position":0,"color":"#0000ff"},{"position":0.5,"color":[0,255,0,128]},{"position":1,"color":[255,0,0]}]})",
      R"({"function":"checker","checker_size":0.31})",
      R"({"function":"custom","lookup":{"dims":[2,1,3],"colors":["#ff0000","#00ff00","#0000ff","#ffff00","#00ffff","#ff00ff"]}})"};
  const std::vector<std::string> images = {"section?axis=x&index=" + std::to_string(grid.at("dims")[0].get<int>() / 2),
                                           "section?axis=y&index=17", "section?axis=z&index=9", "preview?view=%2Bz",
                                           "preview?view=-y"};
  for (const std::string& function : functions) {
    SCOPED_TRACE(function);
    const std::string sliced = finished(submit(stl, "{" + kGrid + R"(,"mode":"slice","slice":)" + function + "}"));
    ASSERT_EQ(expect_json(http().Get(("/v1/jobs/" + sliced).c_str()), 200, "JobStatus").at("grid"), grid);
    for (const std::string& image : images) {
      SCOPED_TRACE(image);
      const auto live = http().Get(("/v1/jobs/" + solid + "/" + image + "&colour=slice&slice=" + escaped(function)).c_str());
      ASSERT_TRUE(live);
      ASSERT_EQ(live->status, 200) << live->body;
      EXPECT_EQ(live->get_header_value("Content-Type"), "image/png");
      const auto made = http().Get(("/v1/jobs/" + sliced + "/" + image).c_str());
      ASSERT_EQ(made->status, 200) << made->body;
      const json a = read_png(live->body), b = read_png(made->body);
      EXPECT_EQ(a.at("width"), b.at("width"));
      EXPECT_EQ(a.at("height"), b.at("height"));
      EXPECT_TRUE(a.at("pixels") == b.at("pixels")) << "the live colours differ from the slice job's";
    }
  }
}

TEST_F(SliceEditingTest, TheFunctionIsKeptUnderItsMeaningNotItsSpelling) {
  start();
  const std::string solid = finished(submit(to_binary_stl(part()), "{" + kGrid + "}"));
  const std::string base = "/v1/jobs/" + solid + "/section?axis=z&index=9&colour=slice&slice=";
  const auto first = http().Get((base + escaped(R"({"function":"rock","noise_colors":["#102030",[200,100,50]]})")).c_str());
  ASSERT_EQ(first->status, 200) << first->body;
  EXPECT_EQ(first->get_header_value("X-Voxd-Cache"), "miss");
  // The same function: other key order, colours spelled otherwise, the defaults given.
  const auto again = http().Get(
      (base + escaped(R"({"seed":1,"noise_colors":[[16,32,48,255],"#c86432"],"octaves":4,"function":"rock","axis":[0,0,1]})"))
          .c_str());
  ASSERT_EQ(again->status, 200) << again->body;
  EXPECT_EQ(again->get_header_value("X-Voxd-Cache"), "hit");
  EXPECT_EQ(again->body, first->body);
  // Another seed is another function.
  const auto other = http().Get((base + escaped(R"({"function":"rock","seed":2,"noise_colors":["#102030","#c86432"]})")).c_str());
  ASSERT_EQ(other->status, 200);
  EXPECT_EQ(other->get_header_value("X-Voxd-Cache"), "miss");
  EXPECT_TRUE(read_png(other->body).at("pixels") != read_png(first->body).at("pixels")) << "another seed, other colours";

  // Asked up front in the job JSON, the result is kept under the same key,
  // and the status's URL for it reads it back.
  const std::string rock = R"({"function":"rock","noise_colors":["#102030","#c86432"]})";
  const json job = submit(to_binary_stl(part()), "{" + kGrid + R"(,"analyses":[{"kind":"section","axis":"z","index":9,"colour":"slice","slice":)" +
                                                     rock + "}]}");
  const std::string id = finished(job);
  const json status = expect_json(http().Get(("/v1/jobs/" + id).c_str()), 200, "JobStatus");
  ASSERT_EQ(status.at("analyses").size(), 1u);
  const json& entry = status.at("analyses")[0];
  EXPECT_EQ(entry.at("request").at("slice").at("function"), "rock");
  const std::string url = entry.at("url");
  const auto kept = http().Get(url.c_str());
  ASSERT_EQ(kept->status, 200) << url;
  EXPECT_EQ(kept->get_header_value("X-Voxd-Cache"), "hit");
  EXPECT_EQ(read_png(kept->body).at("pixels"), read_png(first->body).at("pixels"));
}

TEST_F(SliceEditingTest, BadSliceRequestsAreRefusedNamingTheField) {
  start();
  const std::string solid = finished(submit(to_binary_stl(part()), "{" + kGrid + "}"));
  const std::string section = "/v1/jobs/" + solid + "/section?axis=z&index=9";
  const auto detail = [&](const std::string& query) {
    const json p = expect_problem(http().Get((section + query).c_str()), 400, "invalid-query");
    return p.value("detail", std::string());
  };
  EXPECT_NE(detail("&colour=slice").find("required with colour=slice"), std::string::npos);
  EXPECT_NE(detail("&colour=slice&slice=" + escaped("{\"function\":")).find("slice"), std::string::npos);
  EXPECT_NE(detail("&colour=slice&slice=" + escaped(R"({"function":"marble","period":-1})")).find("period"), std::string::npos);
  EXPECT_NE(detail("&colour=slice&slice=" + escaped(R"({"function":"checker","period":1})")).find("applies only to function"),
            std::string::npos);
  EXPECT_NE(detail("&colour=slice&slice=" + escaped(R"({"function":"glass"})")).find("marble"), std::string::npos);
  EXPECT_NE(detail("&slice=" + escaped(R"({"function":"marble"})")).find("only with colour=slice"), std::string::npos);
  // A function over 8 KiB of JSON, asked up front in the job JSON: the URL
  // itself cannot be that long.
  const json big = expect_problem(
      http().Post("/v1/jobs",
                  httplib::MultipartFormDataItems{
                      {"mesh", text_of(to_binary_stl(part())), "part.stl", "model/stl"},
                      {"params",
                       "{" + kGrid + R"(,"analyses":[{"kind":"preview","colour":"slice","slice":{"function":"rock","x":")" +
                           std::string(9000, 'a') + "\"}}]}",
                       "", ""}}),
      422, "invalid-params");
  EXPECT_EQ(big.at("errors")[0].at("path"), "/analyses/0/slice");
  EXPECT_NE(big.at("errors")[0].at("message").get<std::string>().find("8192"), std::string::npos) << big;
  // The preview takes the same field, with the same checks.
  const json p = expect_problem(
      http().Get(("/v1/jobs/" + solid + "/preview?colour=slice&slice=" + escaped(R"({"function":"wood","octaves":17})")).c_str()),
      400, "invalid-query");
  EXPECT_NE(p.value("detail", std::string()).find("octaves"), std::string::npos);
}

}  // namespace
}  // namespace voxd::test
