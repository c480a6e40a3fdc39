// PNG stacks in a ZIP, read back by independent readers: Python's zipfile
// (archive structure, CRCs, deflate) and tests/tools/read_png.py (zlib and
// struct, no libpng) for the images.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "support/run_process.h"
#include "support/test_checks.h"
#include "support/test_meshes.h"
#include "voxd/error.h"
#include "voxd/encode/png_image.h"
#include "voxd/encode/png_stack.h"
#include "voxd/encode/zip_archive.h"

namespace voxd {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using test::code_of;
using test::decode_png;

// Checks the archive with zipfile.testzip() (every CRC), extracts it into
// `dir`, and prints each entry's name, method, date, size and Unix mode.
constexpr const char* kReadZip = R"(import json, sys, zipfile
z = zipfile.ZipFile(sys.argv[1])
bad = z.testzip()
if bad is not None:
    sys.exit("bad CRC in " + bad)
z.extractall(sys.argv[2])
print(json.dumps([{"name": i.filename, "method": i.compress_type, "date": list(i.date_time),
                   "size": i.file_size, "mode": i.external_attr >> 16} for i in z.infolist()]))
)";

struct Unzipped {
  json entries = json::array();
  fs::path dir;
};

class ZipTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = test::make_temp_dir("voxd-zip"); }
  void TearDown() override { fs::remove_all(dir_); }

  // The archive as Python's zipfile sees it; fails the test when it refuses it.
  Unzipped unzip(const std::vector<std::uint8_t>& archive) {
    const fs::path zip = fs::path(dir_) / ("archive" + std::to_string(serial_) + ".zip");
    const fs::path script = fs::path(dir_) / "read_zip.py";
    Unzipped u;
    u.dir = fs::path(dir_) / ("out" + std::to_string(serial_++));
    test::write_file(zip.string(), archive);
    test::write_file(script.string(), std::vector<std::uint8_t>(kReadZip, kReadZip + std::strlen(kReadZip)));
    const test::ProcessResult r =
        test::run_process("/usr/bin/python3 " + script.string() + " " + zip.string() + " " + u.dir.string());
    EXPECT_EQ(r.exit_code, 0) << r.err;
    if (r.exit_code == 0) u.entries = json::parse(r.out);
    return u;
  }

  std::string dir_;
  int serial_ = 0;
};

// Colours that differ in every channel by position, some voxels empty, and
// an empty voxel whose r, g, b are not 0 (written as stored).
DenseVolume<Rgba8> coloured(std::int64_t nx, std::int64_t ny, std::int64_t nz) {
  Grid g;
  g.origin = {-2.5, 1.0, 0.125};
  g.voxel_size = 0.25;
  g.dims = {nx, ny, nz};
  DenseVolume<Rgba8> v(g);
  for (std::int64_t k = 0; k < nz; ++k)
    for (std::int64_t j = 0; j < ny; ++j)
      for (std::int64_t i = 0; i < nx; ++i)
        v.at(i, j, k) = Rgba8{static_cast<std::uint8_t>(10 * i + 1), static_cast<std::uint8_t>(20 * j + 2),
                              static_cast<std::uint8_t>(30 * k + 3),
                              static_cast<std::uint8_t>((i + j + k) % 3 == 0 ? 0 : 100 + i + j)};
  v.at(1, 1, 0) = Rgba8{7, 8, 9, 0};
  return v;
}

// The pixels layer k should have: rows from the highest y down.
std::vector<std::uint32_t> expected_layer(const DenseVolume<Rgba8>& v, std::int64_t k) {
  std::vector<std::uint32_t> px;
  for (std::int64_t row = 0; row < v.grid().dims.y; ++row) {
    const std::int64_t j = v.grid().dims.y - 1 - row;
    for (std::int64_t i = 0; i < v.grid().dims.x; ++i) {
      const Rgba8 c = v.at(i, j, k);
      px.insert(px.end(), {c.r, c.g, c.b, c.a});
    }
  }
  return px;
}

std::vector<std::uint8_t> bytes_of(const std::string& s) { return {s.begin(), s.end()}; }

TEST(PngRgba8, ExactSamples) {
  const std::vector<std::uint8_t> px = {0, 1, 2, 3, 255, 254, 253, 0, 9, 8, 7, 128, 1, 1, 1, 1, 50, 60, 70, 80, 0, 0, 0, 255};
  VectorSink sink;
  write_png_rgba8(3, 2, px, {{"voxd:layer", "4"}}, sink);
  const json png = decode_png(sink.data);
  EXPECT_EQ(png["width"], 3);
  EXPECT_EQ(png["height"], 2);
  EXPECT_EQ(png["bit_depth"], 8);
  EXPECT_EQ(png["color_type"], 6);
  EXPECT_EQ(png["pixels"].get<std::vector<std::uint32_t>>(), std::vector<std::uint32_t>(px.begin(), px.end()));
  EXPECT_EQ(png["text"]["voxd:layer"], "4");
}

TEST(PngRgba8, RefusesBadSizes) {
  VectorSink sink;
  const std::vector<std::uint8_t> px(24, 0);
  EXPECT_EQ(code_of([&] { write_png_rgba8(3, 3, px, {}, sink); }), ErrorCode::invalid_argument);
  EXPECT_EQ(code_of([&] { write_png_rgba8(6, 1, std::span(px).first(23), {}, sink); }), ErrorCode::invalid_argument);
  EXPECT_EQ(code_of([&] { write_png_rgba8(0, 6, px, {}, sink); }), ErrorCode::invalid_argument);
}

TEST(PngStack, LayerNames) {
  EXPECT_EQ(png_layer_name(0), "layer-00000.png");
  EXPECT_EQ(png_layer_name(42), "layer-00042.png");
  EXPECT_EQ(png_layer_name(65535), "layer-65535.png");
}

TEST_F(ZipTest, StackHoldsManifestThenEveryLayer) {
  const DenseVolume<Rgba8> vol = coloured(7, 5, 4);
  VectorSink sink;
  write_png_stack_zip(vol, sink);
  const Unzipped u = unzip(sink.data);
  ASSERT_EQ(u.entries.size(), 5u);
  EXPECT_EQ(u.entries[0]["name"], "manifest.json");
  EXPECT_EQ(u.entries[0]["method"], 8);  // deflated
  for (int k = 0; k < 4; ++k) {
    const json& e = u.entries[static_cast<std::size_t>(k + 1)];
    EXPECT_EQ(e["name"], png_layer_name(k));
    EXPECT_EQ(e["method"], 0) << "PNGs are stored";
  }
  for (const json& e : u.entries) {
    EXPECT_EQ(e["date"], json::parse("[1980, 1, 1, 0, 0, 0]"));
    EXPECT_EQ(e["mode"], 0100644);
  }

  const json manifest = json::parse(test::read_file((u.dir / "manifest.json").string()));
  EXPECT_EQ(manifest["layers"], 4);
  EXPECT_EQ(manifest["width"], 7);
  EXPECT_EQ(manifest["height"], 5);
  EXPECT_EQ(manifest["voxel_size"], 0.25);
  EXPECT_EQ(manifest["origin"], json::parse("[-2.5, 1.0, 0.125]"));
  EXPECT_EQ(manifest["axis"], "z");
  EXPECT_EQ(manifest["row_order"], "y descending");

  for (std::int64_t k = 0; k < 4; ++k) {
    const auto png_bytes = test::read_file((u.dir / png_layer_name(k)).string());
    const json png = decode_png(png_bytes);
    EXPECT_EQ(png["width"], 7);
    EXPECT_EQ(png["height"], 5);
    EXPECT_EQ(png["color_type"], 6);
    EXPECT_EQ(png["pixels"].get<std::vector<std::uint32_t>>(), expected_layer(vol, k)) << "layer " << k;
    EXPECT_EQ(png["text"]["voxd:layer"], std::to_string(k));
    EXPECT_EQ(png["text"]["voxd:axis"], "z");
    EXPECT_EQ(png["text"]["voxd:voxel_size"], "0.25");
    // The single-layer writer gives the same image the ZIP holds.
    VectorSink one;
    write_png_layer(vol, k, one);
    EXPECT_EQ(one.data, png_bytes) << "layer " << k;
  }
}

TEST(PngStack, RowZeroIsTheHighestY) {
  // One marked voxel at the top-left as seen from +z: x = 0, y = dims.y - 1.
  Grid g;
  g.dims = {3, 4, 1};
  DenseVolume<Rgba8> vol(g);
  vol.at(0, 3, 0) = Rgba8{255, 0, 0, 255};
  VectorSink sink;
  write_png_layer(vol, 0, sink);
  const auto px = decode_png(sink.data)["pixels"].get<std::vector<std::uint32_t>>();
  ASSERT_EQ(px.size(), 3u * 4u * 4u);
  EXPECT_EQ(std::vector<std::uint32_t>(px.begin(), px.begin() + 4), (std::vector<std::uint32_t>{255, 0, 0, 255}));
  EXPECT_EQ(std::count(px.begin(), px.end(), 255u), 2);
}

TEST(PngStack, StackIsReproducible) {
  const DenseVolume<Rgba8> vol = coloured(6, 3, 5);
  VectorSink a, b;
  write_png_stack_zip(vol, a);
  write_png_stack_zip(vol, b);
  EXPECT_EQ(a.data, b.data);
}

TEST_F(ZipTest, WriterRoundTripsStoredAndDeflatedEntries) {
  std::mt19937 rng(7);
  std::vector<std::uint8_t> noise(100000);
  for (auto& b : noise) b = static_cast<std::uint8_t>(rng());
  std::string text;
  for (int i = 0; i < 5000; ++i) text += "line " + std::to_string(i % 17) + "\n";
  const std::vector<std::uint8_t> repetitive = bytes_of(text);
  const std::vector<std::uint8_t> empty;

  VectorSink sink;
  ZipWriter zip(sink);
  zip.add("noise.bin", noise, true);
  zip.add("text.txt", repetitive, true);
  zip.add("stored/text.txt", repetitive, false);
  zip.add("empty-deflated", empty, true);
  zip.add("empty-stored", empty, false);
  zip.add("d\xC3\xA9j\xC3\xA0.txt", repetitive, false);  // UTF-8 name
  zip.finish();
  zip.finish();  // a second finish writes nothing
  EXPECT_LT(sink.data.size(), noise.size() + 3 * repetitive.size()) << "deflate must have compressed the text";

  const Unzipped u = unzip(sink.data);
  ASSERT_EQ(u.entries.size(), 6u);
  const std::vector<std::pair<std::string, int>> expected = {{"noise.bin", 8},     {"text.txt", 8},
                                                             {"stored/text.txt", 0}, {"empty-deflated", 8},
                                                             {"empty-stored", 0},  {"d\xC3\xA9j\xC3\xA0.txt", 0}};
  for (std::size_t n = 0; n < expected.size(); ++n) {
    EXPECT_EQ(u.entries[n]["name"], expected[n].first);
    EXPECT_EQ(u.entries[n]["method"], expected[n].second) << expected[n].first;
  }
  EXPECT_EQ(test::read_file((u.dir / "noise.bin").string()), noise);
  EXPECT_EQ(test::read_file((u.dir / "text.txt").string()), repetitive);
  EXPECT_EQ(test::read_file((u.dir / "stored" / "text.txt").string()), repetitive);
  EXPECT_TRUE(test::read_file((u.dir / "empty-deflated").string()).empty());
  EXPECT_TRUE(test::read_file((u.dir / "empty-stored").string()).empty());
  EXPECT_EQ(test::read_file((u.dir / "d\xC3\xA9j\xC3\xA0.txt").string()), repetitive);
}

TEST_F(ZipTest, EmptyArchive) {
  VectorSink sink;
  ZipWriter zip(sink);
  zip.finish();
  EXPECT_EQ(sink.data.size(), 22u);  // the end record alone
  EXPECT_TRUE(unzip(sink.data).entries.empty());
}

TEST(ZipWriter, RefusesBadNamesAndUseAfterFinish) {
  VectorSink sink;
  ZipWriter zip(sink);
  const std::vector<std::uint8_t> data = {1, 2, 3};
  EXPECT_EQ(code_of([&] { zip.add("", data, false); }), ErrorCode::invalid_argument);
  EXPECT_EQ(code_of([&] { zip.add("/etc/passwd", data, false); }), ErrorCode::invalid_argument);
  EXPECT_EQ(code_of([&] { zip.add("a\\b", data, false); }), ErrorCode::invalid_argument);
  EXPECT_EQ(code_of([&] { zip.add(std::string("a\0b", 3), data, false); }), ErrorCode::invalid_argument);
  EXPECT_EQ(code_of([&] { zip.add(std::string(65536, 'a'), data, false); }), ErrorCode::invalid_argument);
  EXPECT_TRUE(sink.data.empty()) << "a refused entry writes nothing";
  zip.finish();
  EXPECT_THROW(zip.add("late", data, false), std::logic_error);
}

TEST(ZipWriter, RefusesTheEntryPast65535) {
  VectorSink sink;
  ZipWriter zip(sink);
  const std::vector<std::uint8_t> none;
  for (int i = 0; i < 65535; ++i) zip.add(std::to_string(i), none, false);
  const std::size_t before = sink.data.size();
  EXPECT_EQ(code_of([&] { zip.add("one-too-many", none, false); }), ErrorCode::limit_exceeded);
  EXPECT_EQ(sink.data.size(), before);
}

TEST(PngStack, RefusesWhatItCannotWrite) {
  VectorSink sink;
  EXPECT_EQ(code_of([&] { write_png_stack_zip(DenseVolume<Rgba8>{}, sink); }), ErrorCode::invalid_argument);
  const DenseVolume<Rgba8> vol = coloured(2, 2, 3);
  EXPECT_EQ(code_of([&] { write_png_layer(vol, 3, sink); }), ErrorCode::invalid_argument);
  EXPECT_EQ(code_of([&] { write_png_layer(vol, -1, sink); }), ErrorCode::invalid_argument);
  Grid tall;
  tall.dims = {1, 1, 65535};  // with the manifest, one entry more than a ZIP holds
  EXPECT_EQ(code_of([&] { write_png_stack_zip(DenseVolume<Rgba8>(tall), sink); }), ErrorCode::limit_exceeded);
  Grid bad = vol.grid();
  bad.voxel_size = std::numeric_limits<double>::infinity();
  EXPECT_EQ(code_of([&] { write_png_stack_zip(DenseVolume<Rgba8>(bad), sink); }), ErrorCode::invalid_argument);
  EXPECT_TRUE(sink.data.empty()) << "refused before the first byte";
}

}  // namespace
}  // namespace voxd
