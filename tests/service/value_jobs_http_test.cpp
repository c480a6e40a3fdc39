// Integration tests of the value modes, coverage (Thon et al.) and sdf
// (Jones), through the real `voxd serve`: the values against analytic
// answers in every format that can hold them, clear refusals for those that
// cannot, repeatable stochastic sampling, and values surviving a restart.
#include <zlib.h>

#include <array>
#include <cmath>
#include <cstring>
#include <map>
#include <sstream>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "support/http_fixture.h"
#include "voxd/encode/volume_format.h"

namespace voxd::test {
namespace {

using nlohmann::json;

using ValueJobsTest = HttpServiceTest;

std::string gunzip(const std::string& in) {
  z_stream z{};
  EXPECT_EQ(inflateInit2(&z, 15 + 16), Z_OK);
  std::string out;
  char buf[1 << 15];
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(in.data()));
  z.avail_in = static_cast<uInt>(in.size());
  int rc = Z_OK;
  while (rc == Z_OK) {
    z.next_out = reinterpret_cast<Bytef*>(buf);
    z.avail_out = sizeof buf;
    rc = inflate(&z, Z_NO_FLUSH);
    out.append(buf, sizeof buf - z.avail_out);
  }
  EXPECT_EQ(rc, Z_STREAM_END);
  inflateEnd(&z);
  return out;
}

// Signed distance from p to the box [lo, hi], negative inside.
double box_distance(glm::dvec3 p, glm::dvec3 lo, glm::dvec3 hi) {
  const glm::dvec3 c = 0.5 * (lo + hi), h = 0.5 * (hi - lo);
  const glm::dvec3 q = glm::abs(p - c) - h;
  const double outside = glm::length(glm::max(q, glm::dvec3(0.0)));
  const double inside = std::min(std::max(q.x, std::max(q.y, q.z)), 0.0);
  return outside + inside;
}

// The box's SDF on a 16^3 grid of 0.5 voxels: exact within the band of 3
// voxels (1.5 model units), clamped beyond, in every float format.
TEST_F(ValueJobsTest, SdfOfABoxIsTheAnalyticDistanceInNrrdRawAndRle) {
  start();
  const glm::dvec3 lo(1.5, 1.5, 1.5), hi(6.5, 5.5, 4.5);
  const std::string id = finished(submit(to_binary_stl(make_box(lo, hi)),
                                         R"({"grid":{"voxel_size":0.5,"origin":[0,0,0],"dims":[16,16,16]},"mode":"sdf"})"));
  const json status = expect_json(http().Get(("/v1/jobs/" + id).c_str()), 200, "JobStatus");
  const json& values = status.at("values");
  EXPECT_EQ(values.at("type"), "f32");
  EXPECT_EQ(values.at("quantity"), "signed distance");
  EXPECT_EQ(values.at("unit"), "model units");
  EXPECT_EQ(values.at("sign_convention"), "inside_negative");
  EXPECT_EQ(values.at("band"), 3.0);
  EXPECT_FLOAT_EQ(values.at("min").get<float>(), -1.25f);  // the deepest centres, 1.25 below the top and bottom
  EXPECT_FLOAT_EQ(values.at("max").get<float>(), 1.5f);   // clamped
  // The solid that comes with the values: the voxel centres inside the box.
  EXPECT_EQ(status.at("filled_voxels"), 10 * 8 * 6);

  auto res = http().Get(("/v1/jobs/" + id + "/volume?format=nrrd").c_str());
  ASSERT_EQ(res->status, 200) << res->body;
  EXPECT_EQ(res->get_header_value("Content-Type"), "application/x-nrrd");
  EXPECT_EQ(res->get_header_value("X-Voxd-Value-Type"), "f32");
  const Nrrd nrrd = parse_nrrd(res->body);
  EXPECT_EQ(nrrd.fields.at("type"), "float");
  EXPECT_EQ(nrrd.fields.at("sizes"), "16 16 16");
  EXPECT_EQ(nrrd.fields.at("space origin"), "(0.25,0.25,0.25)");
  EXPECT_EQ(nrrd.fields.at("content"), "signed distance (model units, inside_negative)");
  const std::vector<float> sdf = floats_of(nrrd.data);
  ASSERT_EQ(sdf.size(), 16u * 16 * 16);
  int inside = 0, exact = 0;
  for (int k = 0; k < 16; ++k)
    for (int j = 0; j < 16; ++j)
      for (int i = 0; i < 16; ++i) {
        const double d = box_distance(glm::dvec3(i + 0.5, j + 0.5, k + 0.5) * 0.5, lo, hi);
        const float want = static_cast<float>(std::clamp(d, -1.5, 1.5));
        const float got = sdf[static_cast<std::size_t>(i + 16 * (j + 16 * k))];
        ASSERT_NEAR(got, want, 1e-6) << i << "," << j << "," << k;
        inside += got < 0;
        exact += std::abs(d) < 1.5;
      }
  EXPECT_EQ(inside, 10 * 8 * 6);  // the sign is the solid
  EXPECT_GT(exact, 1000);         // the band is not empty

  // raw is the NRRD's data; gzip NRRD inflates to it; RLE decodes to it with
  // the independent reader.
  EXPECT_EQ(volume(id, "?format=raw"), nrrd.data);
  const Nrrd gz = parse_nrrd(volume(id, "?format=nrrd&encoding=gzip"));
  EXPECT_EQ(gz.fields.at("encoding"), "gzip");
  EXPECT_EQ(gunzip(gz.data), nrrd.data);
  write_file(dir_ + "/v.rle", bytes_of(volume(id, "?format=rle")));
  const auto decoded = run_process("/usr/bin/python3 " + std::string(VOXD_SOURCE_DIR) + "/tests/tools/read_rle.py " + dir_ +
                                   "/v.rle " + dir_ + "/v.f32");
  ASSERT_EQ(decoded.exit_code, 0) << decoded.err;
  EXPECT_EQ(text_of(read_file(dir_ + "/v.f32")), nrrd.data);

  json p;
  // Quantized to u16 levels: within half a level of the floats, the surface
  // (0) a level exactly, offset and scale in the header.
  const std::string q16 = volume(id, "?format=rle&quantize=u16");
  const std::span<const std::uint8_t> q16_bytes(reinterpret_cast<const std::uint8_t*>(q16.data()), q16.size());
  const json quantization = json::parse(read_rle_metadata(q16_bytes)).at("quantization");
  EXPECT_EQ(quantization.at("content"), "signed distance (model units, inside_negative)");
  EXPECT_EQ(quantization.at("offset"), -1.5);
  const double scale = quantization.at("scale");
  const DenseVolume<std::uint16_t> levels = read_rle_u16(q16_bytes);
  ASSERT_EQ(levels.values().size(), sdf.size());
  for (std::size_t i = 0; i < sdf.size(); ++i) ASSERT_NEAR(-1.5 + scale * levels.values()[i], sdf[i], scale / 2 + 1e-9) << i;
  EXPECT_LT(q16.size(), volume(id, "?format=rle").size());
  p = expect_problem(http().Get(("/v1/jobs/" + id + "/volume?format=nrrd&quantize=u8").c_str()), 400, "invalid-query");
  EXPECT_NE(p.at("detail").get<std::string>().find("format rle"), std::string::npos) << p.dump();

  // Formats that cannot hold float values are refused with what to ask for.
  p = expect_problem(http().Get(("/v1/jobs/" + id + "/volume?format=binvox").c_str()), 400, "invalid-query");
  EXPECT_NE(p.at("detail").get<std::string>().find("rle, raw or nrrd"), std::string::npos) << p.dump();
  p = expect_problem(http().Get(("/v1/jobs/" + id + "/volume?format=raw&packing=bits").c_str()), 400, "invalid-query");
  EXPECT_NE(p.at("detail").get<std::string>().find("packing bytes"), std::string::npos) << p.dump();
  expect_problem(http().Get(("/v1/jobs/" + id + "/volume?format=rle&encoding=gzip").c_str()), 400, "invalid-query");
  expect_problem(http().Get(("/v1/jobs/" + id + "/volume?format=nrrd&encoding=bz2").c_str()), 400, "invalid-query");

  // The solid's measurements still work on a value job.
  const json analysis = expect_json(http().Get(("/v1/jobs/" + id + "/analysis?thickness=false").c_str()), 200, "Analysis");
  EXPECT_DOUBLE_EQ(analysis.at("mass_properties").at("voxels").at("volume").get<double>(), 10 * 8 * 6 * 0.125)
      << analysis.dump();
}

// The sdf job's images: its surface rendered from the distances, and its
// sections in grey and in the diverging map.
TEST_F(ValueJobsTest, SdfPreviewRendersTheZeroLevelSetAndSectionsShowTheDistances) {
  start();
  const std::string id = finished(submit(to_binary_stl(make_box({1.5, 1.5, 1.5}, {6.5, 5.5, 4.5})),
                                         R"({"grid":{"voxel_size":0.5,"origin":[0,0,0],"dims":[16,16,16]},"mode":"sdf"})"));
  auto res = http().Get(("/v1/jobs/" + id + "/preview?view=%2Bz").c_str());
  ASSERT_EQ(res->status, 200) << res->body;
  json png = read_png(res->body);
  EXPECT_EQ(png.at("text").at("voxd:render"), "sdf sphere tracing");
  ASSERT_EQ(png.at("width"), 16);
  ASSERT_EQ(png.at("height"), 16);
  ASSERT_EQ(png.at("color_type"), 2);
  // Seen from +z (right +x, up +y, row 0 at the top): each ray runs along a
  // column of voxel centres, so the box's footprint is exactly the columns
  // whose centres it covers, x voxels 3..12 and y voxels 3..10, and its top
  // face, flat and facing the camera, has one colour away from the rim
  // (where the normals' differences reach over the edge).
  const auto& px = png.at("pixels");
  auto rgb = [&](int c, int r) {
    const std::size_t at = static_cast<std::size_t>(3 * (r * 16 + c));
    return std::array<int, 3>{px.at(at).get<int>(), px.at(at + 1).get<int>(), px.at(at + 2).get<int>()};
  };
  const std::array<int, 3> white{255, 255, 255}, face = rgb(7, 8);
  EXPECT_NE(face, white);
  for (int r = 0; r < 16; ++r)
    for (int c = 0; c < 16; ++c) {
      const int i = c, j = 15 - r;
      const bool box = i >= 3 && i <= 12 && j >= 3 && j <= 10;
      const bool interior = i >= 4 && i <= 11 && j >= 4 && j <= 9;
      if (!box) {
        ASSERT_EQ(rgb(c, r), white) << c << "," << r;
      } else {
        ASSERT_NE(rgb(c, r), white) << c << "," << r;
      }
      if (interior) {
        ASSERT_EQ(rgb(c, r), face) << c << "," << r;
      }
    }
  // The voxel preview is still there with colour=thickness (of the solid).
  EXPECT_EQ(read_png(http().Get(("/v1/jobs/" + id + "/preview?view=%2Bz&colour=thickness").c_str())->body)
                .at("text").count("voxd:render"), 0u);

  // Grey section through z voxel 5 (centres at z = 2.75): value v maps to
  // round(127.5 + 127.5 v / R), R = 1.5 (the clamped band, the largest |v|).
  png = read_png(http().Get(("/v1/jobs/" + id + "/section?axis=z&index=5").c_str())->body);
  ASSERT_EQ(png.at("color_type"), 0);
  EXPECT_EQ(png.at("pixels").at(0), 255);                 // voxel (0, 0): far outside, clamped
  EXPECT_EQ(png.at("pixels").at(3 * 16 + 3), 106);        // voxel (3, 3): 0.25 inside
  EXPECT_EQ(png.at("pixels").at(6 * 16 + 7), 21);         // voxel (7, 6): 1.25 inside
  // The diverging map: blue inside, red outside, a legend below.
  png = read_png(http().Get(("/v1/jobs/" + id + "/section?axis=z&index=5&colour=distance").c_str())->body);
  ASSERT_EQ(png.at("color_type"), 2);
  EXPECT_GT(png.at("height").get<int>(), 16);
  const auto& d = png.at("pixels");
  auto at = [&](int i, int j, int ch) { return d.at(static_cast<std::size_t>(3 * (j * 16 + i) + ch)).get<int>(); };
  EXPECT_GT(at(7, 6, 2), at(7, 6, 0) + 50) << "inside is blue";
  EXPECT_GT(at(0, 0, 0), at(0, 0, 2) + 50) << "outside is red";
  // A value section cannot be peeled; a solid job has no distances.
  expect_problem(http().Get(("/v1/jobs/" + id + "/section?axis=z&index=5&peel=1").c_str()), 400, "invalid-query");
  const std::string solid = finished(submit(to_binary_stl(make_box({1.5, 1.5, 1.5}, {6.5, 5.5, 4.5})),
                                            R"({"grid":{"voxel_size":0.5,"origin":[0,0,0],"dims":[16,16,16]}})"));
  const json p = expect_problem(http().Get(("/v1/jobs/" + solid + "/section?axis=z&index=5&colour=distance").c_str()), 400,
                                "invalid-query");
  EXPECT_NE(p.at("detail").get<std::string>().find("sdf job"), std::string::npos) << p.dump();
}

TEST_F(ValueJobsTest, SdfConventionAndUnitsAreTheClientsAndTheFullFieldHasNoClamp) {
  start();
  const glm::dvec3 lo(1.5, 1.5, 1.5), hi(6.5, 5.5, 4.5);
  const std::string id = finished(submit(
      to_binary_stl(make_box(lo, hi)),
      R"({"grid":{"voxel_size":0.5,"origin":[0,0,0],"dims":[16,16,16]},"mode":"sdf","sdf":{"band":"full","sign_convention":"inside_positive","units":"voxels"}})"));
  const std::vector<float> sdf = floats_of(volume(id, "?format=raw"));
  ASSERT_EQ(sdf.size(), 16u * 16 * 16);
  for (int k = 0; k < 16; ++k)
    for (int j = 0; j < 16; ++j)
      for (int i = 0; i < 16; ++i) {
        // Jones's convention, in voxels: minus the distance in model units over 0.5.
        const double d = -box_distance(glm::dvec3(i + 0.5, j + 0.5, k + 0.5) * 0.5, lo, hi) / 0.5;
        ASSERT_NEAR(sdf[static_cast<std::size_t>(i + 16 * (j + 16 * k))], d, 2e-6 * std::max(1.0, std::abs(d)))
            << i << "," << j << "," << k;
      }
}

// A box at sub-voxel offsets, sampled by 4 x 4 rays per column: its faces
// across the rays sit on multiples of 1/4, so the regular rays sample the
// cross-section exactly, and along the rays the integration is exact.
TEST_F(ValueJobsTest, CoverageOfABoxAtSubVoxelOffsetsIsTheAnalyticFraction) {
  start();
  const glm::dvec3 lo(0.3, 0.25, 0.25), hi(3.7, 2.75, 1.75);
  const std::vector<std::uint8_t> mesh = to_binary_stl(make_box(lo, hi));
  const std::string grid = R"("grid":{"voxel_size":1,"origin":[0,0,0],"dims":[6,5,4]})";
  auto fraction = [&](int i, int j, int k) {
    double f = 1;
    for (int a = 0; a < 3; ++a) {
      const double v = a == 0 ? i : a == 1 ? j : k;
      f *= std::max(0.0, std::min(v + 1, hi[a]) - std::max(v, lo[a]));
    }
    return f;
  };
  const std::string bytes_id = finished(submit(mesh, "{" + grid + R"(,"mode":"coverage"})"));
  const json status = expect_json(http().Get(("/v1/jobs/" + bytes_id).c_str()), 200, "JobStatus");
  EXPECT_EQ(status.at("values").at("type"), "u8");
  EXPECT_NEAR(status.at("values").at("covered_volume").get<double>(), 3.4 * 2.5 * 1.5, 1e-4);
  const std::string bytes = volume(bytes_id, "?format=raw");
  ASSERT_EQ(bytes.size(), 6u * 5 * 4);
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j < 5; ++j)
      for (int i = 0; i < 6; ++i)
        ASSERT_EQ(static_cast<std::uint8_t>(bytes[static_cast<std::size_t>(i + 6 * (j + 5 * k))]),
                  std::lround(255 * fraction(i, j, k)))
            << i << "," << j << "," << k;
  // binvox version 2 holds the same bytes, NRRD as uchar.
  const std::string binvox = volume(bytes_id, "?format=binvox");
  const DenseVolume<std::uint8_t> from_binvox =
      read_binvox_u8(std::span(reinterpret_cast<const std::uint8_t*>(binvox.data()), binvox.size()));
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j < 5; ++j)
      for (int i = 0; i < 6; ++i)
        ASSERT_EQ(from_binvox.at(i, j, k), static_cast<std::uint8_t>(bytes[static_cast<std::size_t>(i + 6 * (j + 5 * k))]));
  const Nrrd nrrd = parse_nrrd(volume(bytes_id, "?format=nrrd"));
  EXPECT_EQ(nrrd.fields.at("type"), "uchar");
  EXPECT_EQ(nrrd.data, bytes);

  // f32 values: the fractions themselves.
  const std::string floats_id = finished(submit(mesh, "{" + grid + R"(,"mode":"coverage","coverage":{"values":"f32"}})"));
  const std::vector<float> f = floats_of(volume(floats_id, "?format=raw"));
  ASSERT_EQ(f.size(), 6u * 5 * 4);
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j < 5; ++j)
      for (int i = 0; i < 6; ++i) ASSERT_NEAR(f[static_cast<std::size_t>(i + 6 * (j + 5 * k))], fraction(i, j, k), 1e-6);
  expect_problem(http().Get(("/v1/jobs/" + floats_id + "/volume?format=binvox").c_str()), 400, "invalid-query");

  // A threshold makes bits: coverage >= 0.5 keeps the voxels at least half
  // inside (0.7 x 0.75 = 0.525 at the x ends, 0.375 at the corners is out).
  const std::string bits_id = finished(submit(mesh, "{" + grid + R"(,"mode":"coverage","coverage":{"threshold":0.5}})"));
  const json bits_status = expect_json(http().Get(("/v1/jobs/" + bits_id).c_str()), 200, "JobStatus");
  // Its values entry keeps what the grey levels measured, but the volume is bits.
  EXPECT_FALSE(bits_status.at("values").contains("type"));
  EXPECT_EQ(bits_status.at("values").at("threshold"), 0.5);
  EXPECT_NEAR(bits_status.at("values").at("covered_volume").get<double>(), 3.4 * 2.5 * 1.5, 1e-4);
  int expected = 0;
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j < 5; ++j)
      for (int i = 0; i < 6; ++i) expected += fraction(i, j, k) >= 0.5;
  EXPECT_EQ(bits_status.at("filled_voxels"), expected);
  auto res = http().Get(("/v1/jobs/" + bits_id + "/volume?format=raw&packing=bytes").c_str());
  EXPECT_EQ(res->get_header_value("X-Voxd-Value-Type"), "bit");
  expect_problem(http().Get(("/v1/jobs/" + bits_id + "/volume?format=rle&quantize=u8").c_str()), 400, "invalid-query");
  EXPECT_EQ(parse_nrrd(volume(bits_id, "?format=nrrd")).fields.at("content"), "voxels (1 = filled)");
  expect_problem(http().Get(("/v1/jobs/" + bytes_id + "/volume?format=rle&quantize=u8").c_str()), 400, "invalid-query");

  // A coverage job's section is its grey levels, byte for byte.
  const json png = read_png(http().Get(("/v1/jobs/" + bytes_id + "/section?axis=z&index=1").c_str())->body);
  ASSERT_EQ(png.at("width"), 6);
  ASSERT_EQ(png.at("height"), 5);
  for (int j = 0; j < 5; ++j)
    for (int i = 0; i < 6; ++i)
      ASSERT_EQ(png.at("pixels").at(static_cast<std::size_t>(j * 6 + i)).get<int>(),
                static_cast<std::uint8_t>(bytes[static_cast<std::size_t>(i + 6 * (j + 5 * 1))]));
}

TEST_F(ValueJobsTest, StochasticCoverageRepeatsWithItsSeedAndSynchronousRunsStreamValues) {
  start();
  const std::vector<std::uint8_t> mesh = to_binary_stl(make_icosphere({0, 0, 0}, 1.0, 3));
  auto run = [&](int seed) {
    const std::string params = R"({"grid":{"resolution":24,"padding":1},"mode":"coverage","coverage":{"sampling":"stochastic","rays":2,"seed":)" +
                               std::to_string(seed) + "}}";
    auto res = post_raw(http(), "/v1/voxelize?format=rle", mesh, params, "application/octet-stream");
    EXPECT_EQ(res->status, 200) << res->body;
    EXPECT_EQ(res->get_header_value("X-Voxd-Value-Type"), "u8");
    return res->body;
  };
  const std::string first = run(7);
  EXPECT_EQ(run(7), first);
  EXPECT_NE(run(8), first);
  const DenseVolume<std::uint8_t> v = read_rle_u8(std::span(reinterpret_cast<const std::uint8_t*>(first.data()), first.size()));
  std::uint64_t grey = 0;
  for (std::uint8_t b : v.values()) grey += b > 0 && b < 255;
  EXPECT_GT(grey, 500u);  // the sphere's boundary voxels are grey

  // A synchronous sdf refuses binvox before running anything.
  const json p = expect_problem(post_raw(http(), "/v1/voxelize?format=binvox", mesh, R"({"mode":"sdf"})", "application/octet-stream"),
                                400, "invalid-query");
  EXPECT_NE(p.at("detail").get<std::string>().find("float32"), std::string::npos);
}

TEST_F(ValueJobsTest, ValuesSurviveARestartAndIdenticalSubmissionsShareThem) {
  start();
  const std::vector<std::uint8_t> mesh = to_binary_stl(make_icosphere({0, 0, 0}, 1.0, 3));
  const std::string params = R"({"grid":{"resolution":20,"padding":3},"mode":"sdf"})";
  const std::string id = finished(submit(mesh, params));
  const std::string before = volume(id, "?format=raw");
  ASSERT_EQ(before.size(), 26u * 26 * 26 * 4);
  const json again = submit(mesh, params);
  EXPECT_TRUE(again.at("cached"));
  EXPECT_EQ(again.at("values").at("type"), "f32");
  EXPECT_EQ(volume(again.at("id"), "?format=raw"), before);

  ASSERT_EQ(server_->stop(), 0);
  start();
  EXPECT_EQ(volume(id, "?format=raw"), before);
  // Deleting the original leaves the identical job's values intact.
  EXPECT_EQ(http().Delete(("/v1/jobs/" + id).c_str())->status, 204);
  EXPECT_EQ(volume(again.at("id"), "?format=raw"), before);
}

}  // namespace
}  // namespace voxd::test
