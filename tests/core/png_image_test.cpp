// PNG output, decoded by an independent reader (tests/tools/read_png.py: zlib
// and struct, no libpng) so the tests check the bytes a viewer sees, not
// libpng reading back its own output.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <cmath>
#include <functional>
#include <random>
#include <set>
#include <tuple>
#include <string>
#include <unistd.h>

#include "support/run_process.h"
#include "support/test_checks.h"
#include "support/test_meshes.h"
#include "voxd/encode/colour_map.h"
#include "voxd/error.h"
#include "voxd/encode/png_image.h"
#include "voxd/analysis/radiography.h"
#include "voxd/analysis/section.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd {
namespace {

using nlohmann::json;
using test::code_of;
using test::decode_png;

template <class T>
std::vector<std::uint32_t> widen(const std::vector<T>& v) {
  return std::vector<std::uint32_t>(v.begin(), v.end());
}

// Three steps along x, heights 2, 5 and 9 voxels, depth j 3..8 (as in radiography_test).
BitVolume stepped_block() {
  Grid g;
  g.dims = {16, 12, 13};
  const Mesh steps = test::concat({test::make_box({2, 3, 2}, {6, 9, 4}), test::make_box({6, 3, 2}, {10, 9, 7}),
                                   test::make_box({10, 3, 2}, {14, 9, 11})});
  return voxelize(steps, g, VoxelizeOptions{});
}

TEST(PngGrey16, ExactSamplesAndScaleText) {
  const std::vector<std::uint32_t> values = {0, 1, 2, 255, 256, 257, 4095, 4096, 30000, 65534, 65535, 12, 0, 7, 65535};
  VectorSink sink;
  write_png_grey16(5, 3, values, PngScale{0.125, "mm"}, {{"voxd:axis", "z"}, {"voxd:map", "max"}}, sink);
  const json png = decode_png(sink.data);
  EXPECT_EQ(png["width"], 5);
  EXPECT_EQ(png["height"], 3);
  EXPECT_EQ(png["bit_depth"], 16);
  EXPECT_EQ(png["color_type"], 0);
  EXPECT_EQ(png["pixels"].get<std::vector<std::uint32_t>>(), values);
  EXPECT_EQ(png["text"]["voxd:scale"], "1 pixel value = 0.125 mm");
  EXPECT_EQ(png["text"]["voxd:unit"], "mm");
  EXPECT_EQ(png["text"]["voxd:axis"], "z");
  EXPECT_EQ(png["text"]["voxd:map"], "max");
}

TEST(PngGrey16, RadiographyOfSteppedBlockRoundTrips) {
  const ThicknessImage img = radiography(stepped_block(), 2);
  VectorSink sink;
  write_png_grey16(img.width, img.height, img.total, PngScale{}, {}, sink);
  const json png = decode_png(sink.data);
  EXPECT_EQ(png["width"], 16);
  EXPECT_EQ(png["height"], 12);
  EXPECT_EQ(png["pixels"].get<std::vector<std::uint32_t>>(), std::vector<std::uint32_t>(img.total.begin(), img.total.end()));
  EXPECT_EQ(png["text"]["voxd:scale"], "1 pixel value = 1 voxel");
}

TEST(PngGrey16, LargeRandomImageChecksum) {
  // Big enough for libpng to pick varied row filters, which the reader undoes.
  const int w = 640, h = 300;
  std::vector<std::uint32_t> values(static_cast<std::size_t>(w * h));
  std::mt19937 rng(5);
  std::uint64_t sum = 0;
  for (std::size_t p = 0; p < values.size(); ++p) {
    // Smooth ramps (filters pay off) with noise in one third of the rows.
    const std::uint32_t x = static_cast<std::uint32_t>(p % w), y = static_cast<std::uint32_t>(p / w);
    values[p] = (x * 97 + y * 31) % 65536 + (y % 3 == 0 ? rng() % 64 : 0) % 65536;
    values[p] = std::min<std::uint32_t>(values[p], 65535);
    sum += values[p];
  }
  VectorSink sink;
  write_png_grey16(w, h, values, PngScale{0.05, "in"}, {}, sink);
  const json png = decode_png(sink.data, true);
  EXPECT_EQ(png["sample_count"], values.size());
  EXPECT_EQ(png["sample_sum"].get<std::uint64_t>(), sum);
  EXPECT_EQ(png["text"]["voxd:scale"], "1 pixel value = 0.05 in");
}

TEST(PngGrey16, ValueOver65535IsALimitError) {
  std::vector<std::uint32_t> values(6, 1);
  values[4] = 65536;
  VectorSink sink;
  std::string message;
  EXPECT_EQ(code_of([&] { write_png_grey16(3, 2, values, PngScale{}, {}, sink); }, &message), ErrorCode::limit_exceeded);
  EXPECT_NE(message.find("pixel (1, 1) has value 65536"), std::string::npos) << message;
  EXPECT_NE(message.find("65535"), std::string::npos) << message;
  EXPECT_TRUE(sink.data.empty());
  // A large image's rows are converted on several threads: the pixel named
  // is still the first over the limit in row order, whichever thread
  // reaches which first.
  const int w = 1000, h = 2000;
  std::vector<std::uint32_t> large(static_cast<std::size_t>(w * h), 7);
  large[1999 * 1000 + 5] = 70000;
  large[1500 * 1000 + 900] = 65536;
  large[1500 * 1000 + 901] = 99999;
  large[260 * 1000 + 3] = 80000;
  for (int threads : {1, 2, 7}) {
    VectorSink large_sink;
    EXPECT_EQ(code_of([&] { write_png_grey16(w, h, large, PngScale{}, {}, large_sink, threads); }, &message),
              ErrorCode::limit_exceeded);
    EXPECT_NE(message.find("pixel (3, 260) has value 80000"), std::string::npos) << threads << ": " << message;
    EXPECT_TRUE(large_sink.data.empty());
  }
}

TEST(PngGrey8, CrossSectionRoundTrips) {
  const GreyImage8 s = cross_section(stepped_block(), 1, 4);
  VectorSink sink;
  write_png_grey8(s.width, s.height, s.pixels, {{"voxd:section", "y = 4.5"}}, sink);
  const json png = decode_png(sink.data);
  EXPECT_EQ(png["width"], 16);
  EXPECT_EQ(png["height"], 13);
  EXPECT_EQ(png["bit_depth"], 8);
  EXPECT_EQ(png["color_type"], 0);
  EXPECT_EQ(png["pixels"].get<std::vector<std::uint32_t>>(), widen(s.pixels));
  EXPECT_EQ(png["text"]["voxd:section"], "y = 4.5");
  // The staircase: column 12 (third step) is filled from row 2 to row 10.
  for (int k = 0; k < 13; ++k) EXPECT_EQ(png["pixels"][static_cast<std::size_t>(k * 16 + 12)], k >= 2 && k <= 10 ? 255 : 0);
}

// The chunk types of a PNG, in order (the signature skipped; lengths trusted).
std::vector<std::string> chunk_types(const std::vector<std::uint8_t>& png) {
  std::vector<std::string> types;
  for (std::size_t at = 8; at + 8 <= png.size();) {
    const std::size_t length = (std::size_t{png[at]} << 24) | (std::size_t{png[at + 1]} << 16) |
                               (std::size_t{png[at + 2]} << 8) | png[at + 3];
    types.emplace_back(reinterpret_cast<const char*>(png.data() + at + 4), 4);
    at += 12 + length;
  }
  return types;
}

// Images of 256 KiB of rows or more are filtered and deflated in bands of
// rows on every thread (encode/png_bands.h), 16 of them from 1 MiB. The independent reader, whose
// zlib checks the stream's Adler-32 and which checks every chunk's CRC,
// decodes exactly the samples given, with the text; the bytes are the same
// on 1, 2 and 5 threads. The pixels mix ramps, noise and flat runs, so
// every row filter is chosen somewhere, and every band but the first
// begins after a row of another band.
TEST(PngBands, LargeImagesAreTheirSamplesAndTheSameBytesOnAnyThreads) {
  struct Case {
    const char* name;
    int channels, bit_depth;
    PngCompression compression;
    int width, height;
  };
  const Case cases[] = {{"grey8", 1, 8, PngCompression::balanced, 1100, 1000},
                        {"grey16", 1, 16, PngCompression::balanced, 800, 700},
                        {"rgb8", 3, 8, PngCompression::balanced, 700, 503},
                        {"rgb8 fast", 3, 8, PngCompression::fast, 700, 503},
                        {"rgba8 fast", 4, 8, PngCompression::fast, 520, 509},
                        {"grey8 small", 1, 8, PngCompression::balanced, 601, 450}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const std::size_t samples = static_cast<std::size_t>(c.width) * static_cast<std::size_t>(c.height) * c.channels;
    std::vector<std::uint32_t> values(samples);
    std::mt19937 rng(static_cast<unsigned>(samples));
    const std::uint32_t top = c.bit_depth == 16 ? 65535 : 255;
    for (std::size_t s = 0; s < samples; ++s) {
      const std::size_t p = s / static_cast<std::size_t>(c.channels), x = p % static_cast<std::size_t>(c.width),
                        y = p / static_cast<std::size_t>(c.width);
      std::uint32_t v = 0;
      if (y % 7 == 0) v = rng() % (top + 1);                               // noise
      else if (y % 7 < 4) v = static_cast<std::uint32_t>(x * 37 + y * 11);  // ramps
      else if (x % 50 < 25) v = static_cast<std::uint32_t>(y * 5);        // flat runs
      values[s] = v % (top + 1);
    }
    const std::vector<PngText> text = {{"voxd:view", "bands"}};
    auto write = [&](int threads) {
      VectorSink sink;
      if (c.bit_depth == 16) {
        write_png_grey16(c.width, c.height, values, PngScale{}, text, sink, threads);
      } else {
        const std::vector<std::uint8_t> bytes(values.begin(), values.end());
        if (c.channels == 1) write_png_grey8(c.width, c.height, bytes, text, sink, threads);
        if (c.channels == 3) write_png_rgb8(RgbImage{c.width, c.height, bytes}, text, sink, c.compression, threads);
        if (c.channels == 4) write_png_rgba8(c.width, c.height, bytes, text, sink, c.compression, threads);
      }
      return sink.data;
    };
    const std::vector<std::uint8_t> one = write(1);
    EXPECT_EQ(write(2), one);
    EXPECT_EQ(write(5), one);
    const std::vector<std::string> types = chunk_types(one);
    // Bands of a sixteenth of the image, 64 KiB to 256 KiB of filtered rows.
    const std::size_t filtered = static_cast<std::size_t>(c.height) *
                                 (static_cast<std::size_t>(c.width) * c.channels * c.bit_depth / 8 + 1);
    const auto idat = static_cast<std::size_t>(std::count(types.begin(), types.end(), "IDAT"));
    EXPECT_GE(idat, filtered >= (std::size_t{1} << 20) ? 16u : 4u) << "not written in enough bands";
    EXPECT_LE(idat, 17u);
    EXPECT_EQ(types.back(), "IEND");
    const json png = decode_png(one);
    ASSERT_FALSE(png.empty());
    EXPECT_EQ(png["width"], c.width);
    EXPECT_EQ(png["height"], c.height);
    EXPECT_EQ(png["bit_depth"], c.bit_depth);
    EXPECT_EQ(png["text"]["voxd:view"], "bands");
    EXPECT_TRUE(png["pixels"].get<std::vector<std::uint32_t>>() == values);
  }
}

TEST(PngErrors, BadSizesAndTextAreRejectedBeforeWriting) {
  VectorSink sink;
  const std::vector<std::uint8_t> six(6, 0);
  EXPECT_EQ(code_of([&] { write_png_grey8(4, 2, six, {}, sink); }), ErrorCode::invalid_argument);
  EXPECT_EQ(code_of([&] { write_png_grey8(0, 0, {}, {}, sink); }), ErrorCode::invalid_argument);
  EXPECT_EQ(code_of([&] { write_png_grey8(3, 2, six, {{"", "x"}}, sink); }), ErrorCode::invalid_argument);
  EXPECT_EQ(code_of([&] { write_png_grey8(3, 2, six, {{std::string(80, 'k'), "x"}}, sink); }), ErrorCode::invalid_argument);
  EXPECT_EQ(code_of([&] { write_png_grey8(3, 2, six, {{" lead", "x"}}, sink); }), ErrorCode::invalid_argument);
  EXPECT_EQ(code_of([&] { write_png_grey8(3, 2, six, {{"k", std::string("a\0b", 3)}}, sink); }), ErrorCode::invalid_argument);
  EXPECT_EQ(code_of([&] { write_png_rgb8(RgbImage{2, 2, std::vector<std::uint8_t>(11)}, {}, sink); }), ErrorCode::invalid_argument);
  EXPECT_TRUE(sink.data.empty());
}

TEST(PngErrors, FailingSinkErrorComesBackThroughLibpng) {
  // The sink's exception crosses libpng's longjmp error path and is rethrown as is.
  struct FailingSink final : ByteSink {
    using ByteSink::write;
    int calls = 0;
    void write(std::span<const std::uint8_t>) override {
      if (++calls == 2) throw Error(ErrorCode::io_error, "disk full (test)");
    }
  };
  FailingSink sink;
  std::string message;
  EXPECT_EQ(code_of([&] { write_png_grey8(3, 2, std::vector<std::uint8_t>(6, 9), {}, sink); }, &message), ErrorCode::io_error);
  EXPECT_EQ(message, "disk full (test)");
  // And the encoder still works afterwards.
  VectorSink ok;
  write_png_grey8(3, 2, std::vector<std::uint8_t>(6, 9), {}, ok);
  EXPECT_EQ(decode_png(ok.data)["pixels"].get<std::vector<std::uint32_t>>(), std::vector<std::uint32_t>(6, 9));
}

Rgb pixel(const json& png, int x, int y) {
  const std::size_t p = (static_cast<std::size_t>(y) * png["width"].get<std::size_t>() + static_cast<std::size_t>(x)) * 3;
  return {png["pixels"][p].get<std::uint8_t>(), png["pixels"][p + 1].get<std::uint8_t>(), png["pixels"][p + 2].get<std::uint8_t>()};
}

TEST(ThicknessColourMap, PixelsLegendAndTextOfSteppedBlock) {
  const ThicknessImage img = radiography(stepped_block(), 2);  // totals 2, 5, 9 by step
  const ColourMap map = render_thickness_map(img.width, img.height, img.total, ColourMapOptions{});
  EXPECT_EQ(map.range_min, 2u);
  EXPECT_EQ(map.range_max, 9u);
  VectorSink sink;
  write_png_rgb8(map.image, map.text, sink);
  const json png = decode_png(sink.data);
  ASSERT_EQ(png["width"], 16);
  ASSERT_EQ(png["height"], 12 + kLegendHeight);
  EXPECT_EQ(png["bit_depth"], 8);
  EXPECT_EQ(png["color_type"], 2);
  const auto& ramp = thickness_ramp();
  EXPECT_EQ(ramp_index(5, 2, 9), 109);  // round(3 * 255 / 7)
  for (int j = 0; j < 12; ++j) {
    for (int i = 0; i < 16; ++i) {
      Rgb want = kNoMaterialColour;
      if (j >= 3 && j <= 8 && i >= 2 && i <= 13) want = ramp[i <= 5 ? 0 : i <= 9 ? 109 : 255];
      EXPECT_EQ(pixel(png, i, j), want) << i << "," << j;
    }
  }
  // Legend: background row, bar from ramp[0] (x = 2) to ramp[255] (x = 13), ticks, labels "2" and "9".
  const int top = 12;
  EXPECT_EQ(pixel(png, 7, top), kLegendBackground);
  EXPECT_EQ(pixel(png, 2, top + kLegendMargin), ramp[0]);
  EXPECT_EQ(pixel(png, 13, top + kLegendMargin + kLegendBarRows - 1), ramp[255]);
  EXPECT_EQ(pixel(png, 1, top + kLegendMargin), kLegendBackground);
  EXPECT_EQ(pixel(png, 14, top + kLegendMargin), kLegendBackground);
  const int tick_row = top + kLegendMargin + kLegendBarRows;
  for (int x = 0; x < 16; ++x) {  // bar_w = 11: ticks at 2 + round(q * 11 / 4) = 2, 5, 8, 10, 13
    const bool tick = x == 2 || x == 5 || x == 8 || x == 10 || x == 13;
    EXPECT_EQ(pixel(png, x, tick_row), tick ? kLegendInk : kLegendBackground) << x;
  }
  // '2' is rows 111/001/111/100/111 at x 2..4; '9' is 111/101/111/001/111 at x 11..13.
  const int ly = top + kLegendLabelRow;
  const char* two[5] = {"###", "..#", "###", "#..", "###"};
  const char* nine[5] = {"###", "#.#", "###", "..#", "###"};
  for (int r = 0; r < 5; ++r) {
    for (int c = 0; c < 3; ++c) {
      EXPECT_EQ(pixel(png, 2 + c, ly + r), two[r][c] == '#' ? kLegendInk : kLegendBackground) << "2 at " << c << "," << r;
      EXPECT_EQ(pixel(png, 11 + c, ly + r), nine[r][c] == '#' ? kLegendInk : kLegendBackground) << "9 at " << c << "," << r;
    }
  }
  EXPECT_EQ(png["text"]["voxd:min"], "2 voxel");
  EXPECT_EQ(png["text"]["voxd:max"], "9 voxel");
  EXPECT_EQ(png["text"]["voxd:scale"], "1 pixel value = 1 voxel");
  EXPECT_EQ(png["text"]["voxd:no_material"], "rgb(255,255,255)");
}

TEST(ThicknessColourMap, ExplicitRangeClampsAndScaleGoesToText) {
  const std::vector<std::uint32_t> values = {0, 1, 4, 10, 20, 30, 0, 100};
  ColourMapOptions o;
  o.scale = {0.5, "mm"};
  o.range_min = 10;
  o.range_max = 30;
  const ColourMap map = render_thickness_map(4, 2, values, o);
  ASSERT_EQ(map.image.height, 2);  // narrower than kLegendMinWidth: no legend
  VectorSink sink;
  write_png_rgb8(map.image, map.text, sink);
  const json png = decode_png(sink.data);
  const auto& ramp = thickness_ramp();
  const Rgb want[8] = {kNoMaterialColour, ramp[0], ramp[0], ramp[0], ramp[128], ramp[255], kNoMaterialColour, ramp[255]};
  for (int p = 0; p < 8; ++p) EXPECT_EQ(pixel(png, p % 4, p / 4), want[p]) << p;
  EXPECT_EQ(png["text"]["voxd:min"], "5 mm");
  EXPECT_EQ(png["text"]["voxd:max"], "15 mm");
  EXPECT_EQ(png["text"]["voxd:scale"], "1 pixel value = 0.5 mm");
  EXPECT_EQ(png["text"]["voxd:legend"], "none");
  o.range_min = 31;
  EXPECT_EQ(code_of([&] { render_thickness_map(4, 2, values, o); }), ErrorCode::invalid_argument);
}

TEST(ThicknessColourMap, RowsOnAnyThreadCountAreEachValuesRampColour) {
  // 301 rows of 37 pixels: several pieces of rows on several threads. The
  // smallest value sits in the first rows and the largest in the last, so
  // the range is found only by joining every piece's.
  const int width = 37, height = 301;
  std::vector<std::uint32_t> values(static_cast<std::size_t>(width) * height);
  std::mt19937 rng(40);
  std::uniform_int_distribution<std::uint32_t> wall(100, 9000);
  for (auto& v : values) v = rng() % 10 < 3 ? 0 : wall(rng);
  values[5 * width + 3] = 7;
  values[300 * width + 36] = 9001;
  std::uint32_t lo = UINT32_MAX, hi = 0;
  for (const std::uint32_t v : values)
    if (v != 0) lo = std::min(lo, v), hi = std::max(hi, v);
  ASSERT_EQ(lo, 7u);
  ASSERT_EQ(hi, 9001u);
  const auto& ramp = thickness_ramp();
  const ColourMap one = render_thickness_map(width, height, values, {}, 1);
  for (const int threads : {1, 3, 0}) {
    const ColourMap map = render_thickness_map(width, height, values, {}, threads);
    EXPECT_EQ(map.range_min, lo) << threads;
    EXPECT_EQ(map.range_max, hi) << threads;
    ASSERT_EQ(map.image.height, height + kLegendHeight);
    for (std::size_t p = 0; p < values.size(); ++p) {
      // round((v - lo) * 255 / (hi - lo)), halves up, in doubles: exact here.
      const Rgb want = values[p] == 0 ? kNoMaterialColour
                                      : ramp[static_cast<std::size_t>(std::floor(
                                            (values[p] - lo) * 255.0 / (hi - lo) + 0.5))];
      const Rgb got{map.image.pixels[3 * p], map.image.pixels[3 * p + 1], map.image.pixels[3 * p + 2]};
      ASSERT_EQ(got, want) << "pixel " << p << " on " << threads << " threads";
    }
    EXPECT_EQ(map.image.pixels, one.image.pixels) << threads;  // the legend too
  }
  // No material at all: the range is 0 to 0 on any thread count.
  const std::vector<std::uint32_t> none(values.size(), 0);
  for (const int threads : {1, 3}) {
    const ColourMap empty = render_thickness_map(width, height, none, {}, threads);
    EXPECT_EQ(empty.range_min, 0u);
    EXPECT_EQ(empty.range_max, 0u);
  }
}

double luminance(Rgb c) {
  auto lin = [](std::uint8_t v) {
    const double s = v / 255.0;
    return s <= 0.04045 ? s / 12.92 : std::pow((s + 0.055) / 1.055, 2.4);
  };
  return 0.2126 * lin(c.r) + 0.7152 * lin(c.g) + 0.0722 * lin(c.b);
}

TEST(ThicknessColourMap, RampIsPerceptuallyOrdered) {
  const auto& ramp = thickness_ramp();
  // Brighter with thickness (up to 8-bit rounding between neighbours).
  for (int i = 0; i + 4 < 256; ++i) EXPECT_LT(luminance(ramp[i]), luminance(ramp[i + 4])) << i;
  // Dark violet to yellow, every entry darker than the no-material colour.
  EXPECT_GT(ramp[0].b, ramp[0].g);
  EXPECT_GT(ramp[0].r, ramp[0].g);
  EXPECT_LT(luminance(ramp[0]), 0.05);
  EXPECT_GT(ramp[255].r, 2 * ramp[255].b);
  EXPECT_GT(ramp[255].g, 2 * ramp[255].b);
  EXPECT_LT(luminance(ramp[255]), luminance(kNoMaterialColour) - 0.1);
  std::set<std::tuple<int, int, int>> distinct;
  for (const Rgb& c : ramp) distinct.insert({c.r, c.g, c.b});
  EXPECT_GE(distinct.size(), 250u);
}

}  // namespace
}  // namespace voxd
