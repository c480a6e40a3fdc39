// Streamed jobs over HTTP (issue #14): a job made slab by slab into its
// stored RLE answers every volume format and every analysis that streams
// with the bytes of the same job made in memory; what needs the whole grid
// runs while it fits the per-job memory and past it answers a 422 that
// names the largest grid it accepts. The real `voxd serve` on loopback.
#include <algorithm>
#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "support/http_client.h"
#include "support/http_fixture.h"
#include "support/test_meshes.h"
#include "support/test_parts.h"

namespace voxd::test {
namespace {

using nlohmann::json;

// An organic closed part (test_parts.h) as a user uploads it.
std::vector<std::uint8_t> blob_stl() { return test::to_binary_stl(test::part_mesh("blob.stl")); }

// A PNG without its tEXt chunks: two jobs' images differ only in the job id
// they carry.
std::string png_pixels_and_header(const std::string& png) {
  EXPECT_GT(png.size(), 8u);
  std::string out = png.substr(0, 8);
  for (std::size_t at = 8; at + 12 <= png.size();) {
    const auto b = [&](std::size_t i) { return static_cast<std::uint32_t>(static_cast<unsigned char>(png[at + i])); };
    const std::uint32_t length = b(0) << 24 | b(1) << 16 | b(2) << 8 | b(3);
    const std::string type = png.substr(at + 4, 4);
    if (type != "tEXt") out += png.substr(at, 12 + length);
    at += 12 + length;
  }
  return out;
}

class StreamedJobsHttpTest : public HttpServiceTest {
 protected:
  std::string get_ok(const std::string& path) {
    auto res = http().Get(path.c_str());
    EXPECT_TRUE(res);
    if (!res) return {};
    EXPECT_EQ(res->status, 200) << path << ": " << res->body;
    return res->body;
  }
};

TEST_F(StreamedJobsHttpTest, AStreamedJobAnswersWithTheInMemoryJobsBytes) {
  start();
  const auto mesh = blob_stl();
  // 91 x 89 x 71: z is not a multiple of any slab the service picks.
  const json in_memory = submit(mesh, R"({"grid":{"resolution":91,"padding":1},"streaming":"off"})");
  const json streamed = submit(mesh, R"({"grid":{"resolution":91,"padding":1},"streaming":"on"})");
  EXPECT_FALSE(in_memory.at("streamed"));
  EXPECT_TRUE(streamed.at("streamed"));
  const std::string a = finished(in_memory), b = finished(streamed);
  const json done = wait_for_job(http(), b);
  EXPECT_TRUE(done.at("streamed"));
  EXPECT_TRUE(done.at("timings").contains("voxelize+write")) << done.dump();
  EXPECT_EQ(done.at("filled_voxels"), wait_for_job(http(), a).at("filled_voxels"));

  for (const char* query : {"", "?format=rle", "?format=raw", "?format=raw&packing=bits", "?format=nrrd",
                            "?format=nrrd&encoding=gzip", "?format=binvox"}) {
    const std::string expected = volume(a, query);
    ASSERT_GT(expected.size(), 100u) << query;
    EXPECT_TRUE(volume(b, query) == expected) << query;
  }
  EXPECT_EQ(volume(b), cli_volume(mesh, "blob.stl", R"({"grid":{"resolution":91,"padding":1}})"));

  // What streams: every radiography, sections along each axis, shaded
  // previews from every side, the analysis without thickness and skin. What
  // needs the whole grid fits here and loads it: the same bytes either way.
  std::vector<std::string> json_routes = {"analysis?thickness=false&skin=false", "analysis"};
  std::vector<std::string> png_routes;
  for (const char* axis : {"x", "y", "z"}) {
    for (const char* measure : {"min", "max", "total"})
      json_routes.push_back(std::string("radiography?axis=") + axis + "&measure=" + measure + "&format=json");
    png_routes.push_back(std::string("radiography?axis=") + axis);
    png_routes.push_back(std::string("section?axis=") + axis + "&index=40");
  }
  for (const char* view : {"%2Bx", "-x", "%2By", "-y", "%2Bz", "-z"}) png_routes.push_back(std::string("preview?view=") + view);
  png_routes.push_back("section?axis=z&index=30&colour=thickness");
  // Issue #39: a preview shrunk to a size (here 30 pixels: each pixel 4 x 4
  // voxels) or at full size, streamed or not.
  png_routes.push_back("preview?view=-y&size=30");
  png_routes.push_back("preview?view=%2Bz&size=full");
  for (const std::string& size : {std::string("30"), std::string("full")}) {
    const std::string png = get_ok("/v1/jobs/" + b + "/preview?view=-y&size=" + size);
    auto be32 = [&](std::size_t at) {
      return (std::uint32_t{static_cast<std::uint8_t>(png[at])} << 24) | (std::uint32_t{static_cast<std::uint8_t>(png[at + 1])} << 16) |
             (std::uint32_t{static_cast<std::uint8_t>(png[at + 2])} << 8) | std::uint32_t{static_cast<std::uint8_t>(png[at + 3])};
    };
    const json grid = done.at("grid").at("dims");
    const auto wide = grid.at(0).get<std::uint32_t>(), high = grid.at(2).get<std::uint32_t>();  // -y: right +x, up +z
    const std::uint32_t factor = size == "full" ? 1 : (std::max(wide, high) + 29) / 30;
    EXPECT_EQ(be32(16), (wide + factor - 1) / factor) << size;  // IHDR width, height
    EXPECT_EQ(be32(20), (high + factor - 1) / factor) << size;
    EXPECT_EQ(png.find("voxd:shrunk") != std::string::npos, size != "full") << size;
  }
  for (const std::string& route : json_routes) {
    const std::string expected = get_ok("/v1/jobs/" + a + "/" + route);
    const std::string got = get_ok("/v1/jobs/" + b + "/" + route);
    EXPECT_EQ(got, expected) << route;
    if (route.rfind("analysis", 0) == 0) schemas_->add("Analysis", got);
  }
  for (const std::string& route : png_routes) {
    const std::string expected = get_ok("/v1/jobs/" + a + "/" + route);
    const std::string got = get_ok("/v1/jobs/" + b + "/" + route);
    EXPECT_EQ(png_pixels_and_header(got), png_pixels_and_header(expected)) << route;
  }
  const json analysis = json::parse(get_ok("/v1/jobs/" + b + "/analysis?thickness=false&skin=false"));
  EXPECT_TRUE(analysis.at("skin").is_null());
  EXPECT_TRUE(analysis.at("thickness").is_null());
  // The parts hold every filled voxel the engine counted while voxelizing.
  EXPECT_GE(analysis.at("parts").at("count"), 1);
  EXPECT_EQ(analysis.at("parts").at("total_voxels"), done.at("filled_voxels"));
}

TEST_F(StreamedJobsHttpTest, AStreamedCoverageJobAnswersWithTheInMemoryJobsBytes) {
  start();
  const auto mesh = blob_stl();
  for (const char* coverage : {"{}", R"({"values":"f32"})", R"({"threshold":0.3})"}) {
    SCOPED_TRACE(coverage);
    const std::string params = std::string(R"({"grid":{"resolution":67,"padding":1},"mode":"coverage","coverage":)") + coverage;
    const json in_memory = submit(mesh, params + R"(,"streaming":"off"})");
    const json streamed = submit(mesh, params + R"(,"streaming":"on"})");
    EXPECT_TRUE(streamed.at("streamed"));
    const std::string a = finished(in_memory), b = finished(streamed);
    const json done_a = wait_for_job(http(), a), done_b = wait_for_job(http(), b);
    // The covered volume to the last bit, the type and unit; the solid's count.
    EXPECT_EQ(done_b.at("values"), done_a.at("values"));
    EXPECT_EQ(done_b.at("filled_voxels"), done_a.at("filled_voxels"));
    EXPECT_GT(done_b.at("filled_voxels").get<std::uint64_t>(), 10000u);

    std::vector<std::string> queries = {"", "?format=raw", "?format=nrrd", "?format=nrrd&encoding=gzip"};
    if (std::string(coverage) != R"({"values":"f32"})") queries.push_back("?format=binvox");  // loaded whole: it fits
    for (const std::string& query : queries) {
      const std::string expected = volume(a, query);
      ASSERT_GT(expected.size(), 100u) << query;
      EXPECT_TRUE(volume(b, query) == expected) << query;
    }
    // Coverage sections in grey levels from the stored values; the preview
    // and the radiography of the solid.
    for (const std::string route : {"section?axis=x&index=30", "section?axis=y&index=20", "section?axis=z&index=33",
                                    "preview?view=-y", "radiography?axis=z"}) {
      EXPECT_EQ(png_pixels_and_header(get_ok("/v1/jobs/" + b + "/" + route)),
                png_pixels_and_header(get_ok("/v1/jobs/" + a + "/" + route)))
          << route;
    }
  }
  // The quantized levels span the whole volume's range: not streamed; this
  // small job's values are loaded whole instead, with the in-memory bytes.
  const std::string params = R"({"grid":{"resolution":40},"mode":"coverage","coverage":{"values":"f32"})";
  const std::string a = finished(submit(mesh, params + R"(,"streaming":"off"})"));
  const std::string b = finished(submit(mesh, params + R"(,"streaming":"on"})"));
  EXPECT_TRUE(volume(b, "?quantize=u8") == volume(a, "?quantize=u8"));
}

TEST_F(StreamedJobsHttpTest, PastThePerJobMemoryAJobStreamsAndWholeGridAnalysesAnswer422NamingTheLargestGrid) {
  // 24 MiB a job: the blob at 700 (700 x 686 x 544 voxels, 33 MB of bits)
  // does not fit in memory, so it streams by itself.
  start({"--max-job-memory", "25165824"});
  const auto mesh = blob_stl();
  const json job = submit(mesh, R"({"grid":{"resolution":700}})");
  EXPECT_TRUE(job.at("streamed")) << job.dump();
  const std::string id = finished(job);

  // The volume streams in every format that streams, as the CLI writes it.
  const std::string rle = volume(id);
  EXPECT_TRUE(rle == cli_volume(mesh, "blob.stl", R"({"grid":{"resolution":700}})"));
  EXPECT_TRUE(volume(id, "?format=nrrd") == cli_volume(mesh, "blob.stl", R"({"grid":{"resolution":700}})", "nrrd"));
  const json binvox = expect_problem(http().Get(("/v1/jobs/" + id + "/volume?format=binvox").c_str()), 422, "limit-exceeded");
  EXPECT_NE(binvox.at("detail").get<std::string>().find("ask for format rle, raw or nrrd"), std::string::npos) << binvox.dump();

  // Radiography and mass properties answer.
  const json radiography =
      json::parse(get_ok("/v1/jobs/" + id + "/radiography?axis=z&measure=total&format=json"));
  EXPECT_EQ(radiography.at("width"), 700);
  const json analysis = json::parse(get_ok("/v1/jobs/" + id + "/analysis?thickness=false&skin=false"));
  const double h = wait_for_job(http(), id).at("grid").at("voxel_size");
  EXPECT_DOUBLE_EQ(analysis.at("mass_properties").at("voxels").at("volume").get<double>(),
                   wait_for_job(http(), id).at("filled_voxels").get<double>() * h * h * h);
  // Sections along every axis; previews from above and from the side.
  for (const char* axis : {"x", "y", "z"}) get_ok(std::string("/v1/jobs/") + id + "/section?axis=" + axis + "&index=300");
  for (const std::string view : {"+z", "-x"}) {
    const std::string png = get_ok("/v1/jobs/" + id + "/preview?view=" + (view[0] == '+' ? "%2B" + view.substr(1) : view));
    EXPECT_NE(png.find(std::string("voxd:view") + '\0' + view), std::string::npos) << view;
  }

  // Wall thickness, skin removal and thickness colours need the whole grid.
  for (const char* route : {"thickness", "analysis", "analysis?thickness=false", "preview?colour=thickness",
                            "radiography?peel=2"}) {
    const json p = expect_problem(http().Get(("/v1/jobs/" + id + "/" + route).c_str()), 422, "limit-exceeded");
    const std::string detail = p.at("detail");
    EXPECT_NE(detail.find("needs the whole grid in memory"), std::string::npos) << route << ": " << detail;
    EXPECT_NE(detail.find("the largest grid it accepts here is"), std::string::npos) << detail;
    EXPECT_NE(detail.find("thickness=false&skin=false"), std::string::npos) << detail;
  }
  // Asked for up front, the job is refused at submission with the same reason.
  const json refused = expect_problem(
      post_multipart(http(), "/v1/jobs", mesh, "blob.stl", R"({"grid":{"resolution":700},"analyses":[{"kind":"thickness"}]})"),
      422, "limit-exceeded");
  EXPECT_NE(refused.at("detail").get<std::string>().find("the wall thickness volume needs the whole grid"), std::string::npos)
      << refused.dump();
  // While one that streams is prepared with the volume.
  const json prepared = submit(mesh, R"({"grid":{"resolution":700},"analyses":[{"kind":"radiography","axis":"x"}]})");
  const std::string prepared_id = finished(prepared);
  const json status = wait_for_job(http(), prepared_id);
  EXPECT_EQ(status.at("analyses").at(0).at("state"), "ready") << status.dump();
}

TEST_F(StreamedJobsHttpTest, StreamingOnForAJobThatCannotStreamSaysWhy) {
  start();
  const json p = expect_problem(post_multipart(http(), "/v1/jobs", blob_stl(), "blob.stl",
                                               R"({"grid":{"resolution":32},"inside":"winding","streaming":"on"})"),
                                422, "invalid-params");
  EXPECT_NE(p.at("detail").get<std::string>().find("\"streaming\": \"on\""), std::string::npos) << p.dump();
  const json sync = expect_problem(post_multipart(http(), "/v1/voxelize", blob_stl(), "blob.stl",
                                                  R"({"grid":{"resolution":32},"streaming":"on"})"),
                                   422, "invalid-params");
  EXPECT_NE(sync.at("detail").get<std::string>().find("POST /v1/jobs"), std::string::npos) << sync.dump();
}

}  // namespace
}  // namespace voxd::test
