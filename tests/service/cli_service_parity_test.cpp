// The CLI and the service write the same bytes and the same metadata for
// the same job: `voxd analyze`'s files against the routes' answers, `voxd
// voxelize`'s value volumes against /volume, and each palette layer's NRRD
// says what that layer holds.
#include <filesystem>
#include <fstream>

#include "support/http_fixture.h"
#include "support/run_process.h"
#include "support/test_meshes.h"

namespace voxd::test {
namespace {

using nlohmann::json;

class CliServiceParity : public HttpServiceTest {
 protected:
  // A PNG as read_png.py decodes it, without the one text chunk that names
  // the job (its id differs between the two).
  json decoded_png(const std::string& bytes, const std::string& name) {
    const std::string file = dir_ + "/decode-" + name;
    std::ofstream(file, std::ios::binary) << bytes;
    const auto r = run_process("/usr/bin/python3 " + std::string(VOXD_SOURCE_DIR) + "/tests/tools/read_png.py " + file);
    EXPECT_EQ(r.exit_code, 0) << name << r.err;
    if (r.exit_code != 0) return json();
    json png = json::parse(r.out);
    EXPECT_TRUE(png.at("text").contains("voxd:job")) << name;
    png.at("text").erase("voxd:job");
    return png;
  }
  std::string get(const std::string& target) {
    auto res = http().Get(target.c_str());
    EXPECT_TRUE(res) << target;
    if (!res) return {};
    EXPECT_EQ(res->status, 200) << target << ": " << res->body;
    return res->body;
  }
  static std::string nrrd_header(const std::string& bytes) { return bytes.substr(0, bytes.find("\n\n")); }
};

TEST_F(CliServiceParity, AnalyzeWritesWhatTheRoutesAnswer) {
  start();
  // A box 4 x 3 x 2 with a non-unit voxel: a scale "in voxels" and one "in
  // model units" would differ.
  const auto mesh = to_binary_stl(make_box({0, 0, 0}, {4, 3, 2}));
  const std::string params = R"({"grid":{"voxel_size":0.25,"padding":1}})";
  write_file(dir_ + "/box.stl", mesh);
  std::ofstream(dir_ + "/params.json") << params;
  const auto cli = run_process(std::string(VOXD_BINARY) + " analyze " + dir_ + "/box.stl -o " + dir_ + "/out --params @" +
                               dir_ + "/params.json");
  ASSERT_EQ(cli.exit_code, 0) << cli.err;
  const std::string id = finished(submit(mesh, params));
  const std::string base = "/v1/jobs/" + id;
  const json status = json::parse(get(base));
  const json dims = status.at("grid").at("dims");
  ASSERT_EQ(dims, json::array({18, 14, 10}));
  auto file = [&](const std::string& name) { return text_of(read_file(dir_ + "/out/" + name)); };

  int compared = 0;
  for (const std::string a : {"x", "y", "z"}) {
    const int axis = a[0] - 'x';
    for (const std::string m : {"min", "max", "total"}) {
      const std::string name = "radiography-" + a + "-" + m + ".png";
      const json mine = decoded_png(file(name), name);
      EXPECT_EQ(mine, decoded_png(get(base + "/radiography?axis=" + a + "&measure=" + m), "http-" + name)) << name;
      EXPECT_EQ(mine.at("text").at("voxd:scale"), "1 pixel value = 1 voxel") << name;
      ++compared;
    }
    const std::string colour = "radiography-" + a + "-max-colour.png";
    EXPECT_EQ(decoded_png(file(colour), colour), decoded_png(get(base + "/radiography?axis=" + a + "&format=png"), "http-" + colour));
    const std::string mid = std::to_string(dims[axis].get<int>() / 2);
    for (const std::string suffix : {"", "-thickness"}) {
      const std::string name = "section-" + a + suffix + ".png";
      const std::string query = "/section?axis=" + a + "&index=" + mid + (suffix.empty() ? "" : "&colour=thickness");
      EXPECT_EQ(decoded_png(file(name), name), decoded_png(get(base + query), "http-" + name)) << name;
      compared += 2;
    }
  }
  for (const std::string view : {"+x", "-z"}) {
    const std::string name = "preview-from" + view + "-thickness.png";
    const std::string query = "/preview?view=" + std::string(view[0] == '+' ? "%2B" : "-") + view.substr(1) + "&colour=thickness";
    EXPECT_EQ(decoded_png(file(name), name), decoded_png(get(base + query), "http-" + name)) << name;
    ++compared;
  }
  // The thickness volume has no job id in it: the very bytes.
  EXPECT_EQ(file("thickness.nrrd"), get(base + "/thickness?format=nrrd"));
  EXPECT_EQ(compared, 3 * 3 + 3 * 2 * 2 + 2);
}

TEST_F(CliServiceParity, ValueVolumesAndTheirHeadersAreTheCliOnes) {
  start();
  const auto mesh = to_binary_stl(make_icosphere({0, 0, 0}, 3.0, 3));
  for (const std::string params : {R"({"mode":"sdf","grid":{"resolution":24,"padding":2},"sdf":{"band":2}})",
                                   R"({"mode":"sdf","grid":{"resolution":20},"sdf":{"band":"full","units":"voxels","sign_convention":"inside_positive"}})",
                                   R"({"mode":"coverage","grid":{"resolution":20},"coverage":{"rays":2}})",
                                   R"({"mode":"coverage","grid":{"resolution":20},"coverage":{"values":"f32"}})"}) {
    SCOPED_TRACE(params);
    const std::string id = finished(submit(mesh, params));
    const std::string served = get("/v1/jobs/" + id + "/volume?format=nrrd");
    const std::string cli = cli_volume(mesh, "ball.stl", params, "nrrd");
    EXPECT_EQ(nrrd_header(served), nrrd_header(cli));
    EXPECT_EQ(served, cli);
  }
}

TEST_F(CliServiceParity, EachPaletteLayerSaysWhatItHolds) {
  start();
  const auto mesh = to_binary_stl(make_icosphere({0, 0, 0}, 3.0, 3));
  const std::string params =
      R"({"mode":"palette","grid":{"resolution":12},"palette":{"elements":10,"rays":4,"points":2,"seed":1,"render":{"full":[{"object":"brick"}]}}})";
  const std::string id = finished(submit(mesh, params));
  const std::string element = nrrd_header(get("/v1/jobs/" + id + "/volume?format=nrrd"));
  EXPECT_NE(element.find("content: palette element (element index"), std::string::npos) << element;
  EXPECT_EQ(element, nrrd_header(cli_volume(mesh, "ball.stl", params, "nrrd")));
  EXPECT_EQ(nrrd_header(get("/v1/jobs/" + id + "/volume?format=nrrd&layer=element")), element);
  const std::string similarity = nrrd_header(get("/v1/jobs/" + id + "/volume?format=nrrd&layer=similarity"));
  EXPECT_NE(similarity.find("content: palette similarity (round(255 x"), std::string::npos) << similarity;
  const std::string display = nrrd_header(get("/v1/jobs/" + id + "/volume?format=nrrd&layer=display"));
  EXPECT_NE(display.find("content: display object (0 = nothing shown"), std::string::npos) << display;
}

// How a job runs is decided in one place (plan_execution): `voxd voxelize`
// into an RLE and a job submitted with the same params report the same path,
// where the modes' own wishes (the band SDF is faster slab by slab) and the
// memory threshold (512 MiB of volumes) decide it.
TEST_F(CliServiceParity, CliAndServiceTakeTheSameExecutionPath) {
  start();
  const auto mesh = to_binary_stl(make_box({0, 0, 0}, {4, 4, 4}));
  write_file(dir_ + "/box.stl", mesh);
  struct Case {
    const char* what;
    std::string params;
    std::string path;
    bool streamed;
  };
  const std::vector<Case> cases = {
      // Small, but the band goes slab by slab whatever its size.
      {"band sdf", R"({"grid":{"resolution":48},"mode":"sdf"})", "slabs", true},
      // 1700^3 voxels, 614 MB of bits: past the threshold, its runs straight into the RLE.
      {"solid past the threshold", R"({"grid":{"resolution":1700}})", "runs", true},
      // 400^3 floats and bits: 264 MB, in memory.
      {"small coverage", R"({"grid":{"resolution":400},"mode":"coverage"})", "memory", false},
      // 520^3 floats and bits: 580 MB, past the threshold.
      {"coverage past the threshold", R"({"grid":{"resolution":520},"mode":"coverage"})", "slabs", true},
  };
  for (const Case& c : cases) {
    std::ofstream(dir_ + "/params.json") << c.params;
    const auto cli = run_process(std::string(VOXD_BINARY) + " voxelize " + dir_ + "/box.stl -o " + dir_ +
                                 "/out.rle --json --params @" + dir_ + "/params.json");
    ASSERT_EQ(cli.exit_code, 0) << c.what << ": " << cli.err;
    const json summary = json::parse(cli.out);
    const json job = wait_for_job(http(), finished(submit(mesh, c.params)));
    EXPECT_EQ(summary.at("execution"), c.path) << c.what;
    EXPECT_EQ(job.at("execution"), c.path) << c.what;
    EXPECT_EQ(summary.at("streamed"), c.streamed) << c.what;
    EXPECT_EQ(job.at("streamed"), c.streamed) << c.what;
    EXPECT_EQ(job.at("filled_voxels"), summary.at("filled_voxels")) << c.what;
    std::filesystem::remove(dir_ + "/out.rle");
  }
}

}  // namespace
}  // namespace voxd::test
