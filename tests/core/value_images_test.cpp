// Sections of value volumes (voxd/analysis/value_images.h) and the diverging colour
// ramp (voxd/encode/colour_map.h): exact pixels against the volume for coverage
// bytes and floats, the signed distance section in colour (inside blue,
// zero white, outside red, whatever the sign convention; legend) and in grey
// (the documented linear map), their tEXt, and the errors for bad planes.
// PNGs are decoded by the independent reader tests/tools/read_png.py.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <string>
#include <unistd.h>

#include "support/run_process.h"
#include "support/test_checks.h"
#include "support/test_meshes.h"
#include "voxd/encode/colour_map.h"
#include "voxd/voxelize/coverage.h"
#include "voxd/error.h"
#include "voxd/analysis/value_images.h"

namespace voxd {
namespace {

using nlohmann::json;
using test::code_of;
using test::decode_png;

// Voxel (i, j, k) shown by pixel (c, r) of a section along `axis` at `index`,
// as section.h documents: axis 0 -> (j, k), 1 -> (i, k), 2 -> (i, j).
std::array<std::int64_t, 3> voxel_of(int axis, std::int64_t index, std::int64_t c, std::int64_t r) {
  if (axis == 0) return {index, c, r};
  if (axis == 1) return {c, index, r};
  return {c, r, index};
}

Rgb pixel(const json& png, std::int64_t x, std::int64_t y) {
  const std::size_t p = (static_cast<std::size_t>(y) * png["width"].get<std::size_t>() + static_cast<std::size_t>(x)) * 3;
  return {png["pixels"][p].get<std::uint8_t>(), png["pixels"][p + 1].get<std::uint8_t>(),
          png["pixels"][p + 2].get<std::uint8_t>()};
}

const Grid kGrid = test::make_grid({7, 5, 4}, {-1.0, 0.5, 2.0}, 0.25);

TEST(CoverageSection, BytesExactlyInEveryPlane) {
  DenseVolume<std::uint8_t> v(kGrid);
  for (std::int64_t k = 0; k < 4; ++k)
    for (std::int64_t j = 0; j < 5; ++j)
      for (std::int64_t i = 0; i < 7; ++i) v.at(i, j, k) = static_cast<std::uint8_t>((i * 37 + j * 11 + k * 101) % 256);
  for (int axis = 0; axis < 3; ++axis) {
    for (std::int64_t index = 0; index < kGrid.dims[axis]; ++index) {
      SCOPED_TRACE("axis " + std::to_string(axis) + " index " + std::to_string(index));
      const json png = decode_png(coverage_section_png(v, axis, index, {{"voxd:job", "j1"}}));
      const int w = static_cast<int>(axis == 0 ? kGrid.dims.y : kGrid.dims.x);
      const int h = static_cast<int>(axis == 2 ? kGrid.dims.y : kGrid.dims.z);
      ASSERT_EQ(png["width"], w);
      ASSERT_EQ(png["height"], h);
      EXPECT_EQ(png["bit_depth"], 8);
      EXPECT_EQ(png["color_type"], 0);
      const auto pixels = png["pixels"].get<std::vector<int>>();
      const ValueSection<std::uint8_t> s = value_section(v, axis, index);
      ASSERT_EQ(s.width, w);
      ASSERT_EQ(s.height, h);
      for (int r = 0; r < h; ++r)
        for (int c = 0; c < w; ++c) {
          const auto ijk = voxel_of(axis, index, c, r);
          EXPECT_EQ(pixels[static_cast<std::size_t>(r * w + c)], v.at(ijk[0], ijk[1], ijk[2]));
          EXPECT_EQ(s.values[static_cast<std::size_t>(r * w + c)], v.at(ijk[0], ijk[1], ijk[2]));
        }
      EXPECT_EQ(png["text"]["voxd:axis"], std::string(1, "xyz"[axis]));
      EXPECT_EQ(png["text"]["voxd:index"], std::to_string(index));
      const double plane = kGrid.origin[axis] + (static_cast<double>(index) + 0.5) * 0.25;
      EXPECT_EQ(png["text"]["voxd:plane"], json(plane).dump() + " model units (voxel centres)");
      EXPECT_EQ(png["text"]["voxd:voxel_size"], "0.25 model units per pixel");
      EXPECT_NE(png["text"]["voxd:coverage"].get<std::string>().find("255"), std::string::npos);
      EXPECT_EQ(png["text"]["voxd:job"], "j1");
    }
  }
}

TEST(CoverageSection, FloatsAsCoverageBytes) {
  DenseVolume<float> v(kGrid);
  const float samples[] = {0.0f, 1.0f, 0.5f, 1.0f / 255.0f, 0.499f / 255.0f, 0.501f / 255.0f, 0.3f, 0.999f, -0.2f, 1.7f};
  std::size_t n = 0;
  for (float& x : v.values()) x = samples[n++ % std::size(samples)];
  const DenseVolume<std::uint8_t> bytes = coverage_bytes(v);
  for (int axis = 0; axis < 3; ++axis) {
    const std::int64_t index = kGrid.dims[axis] - 2;
    const json png = decode_png(coverage_section_png(v, axis, index));
    const auto pixels = png["pixels"].get<std::vector<int>>();
    const int w = png["width"], h = png["height"];
    for (int r = 0; r < h; ++r)
      for (int c = 0; c < w; ++c) {
        const auto ijk = voxel_of(axis, index, c, r);
        const float x = v.at(ijk[0], ijk[1], ijk[2]);
        const int want = static_cast<int>(std::lround(255.0 * std::clamp(static_cast<double>(x), 0.0, 1.0)));
        EXPECT_EQ(pixels[static_cast<std::size_t>(r * w + c)], want) << x;
        EXPECT_EQ(pixels[static_cast<std::size_t>(r * w + c)], bytes.at(ijk[0], ijk[1], ijk[2]));
      }
    // The same picture as the bytes' section.
    EXPECT_EQ(coverage_section_png(v, axis, index), coverage_section_png(bytes, axis, index));
  }
}

TEST(DivergingRamp, WhiteCentreBlueBelowRedAboveSymmetricLightness) {
  const auto& ramp = diverging_ramp();
  EXPECT_EQ(ramp[kDivergingCentre], (Rgb{255, 255, 255}));
  auto luminance = [](Rgb c) {
    auto lin = [](int v) {
      const double e = v / 255.0;
      return e <= 0.04045 ? e / 12.92 : std::pow((e + 0.055) / 1.055, 2.4);
    };
    return 0.2126 * lin(c.r) + 0.7152 * lin(c.g) + 0.0722 * lin(c.b);
  };
  for (int i = 1; i <= kDivergingCentre; ++i) {
    const Rgb blue = ramp[static_cast<std::size_t>(kDivergingCentre - i)];
    const Rgb red = ramp[static_cast<std::size_t>(kDivergingCentre + i)];
    if (i >= 8) {
      EXPECT_GT(blue.b, blue.r + 10) << i;
      EXPECT_GT(red.r, red.b + 10) << i;
    }
    // Mirror-image brightness, falling steadily away from white.
    EXPECT_NEAR(luminance(blue), luminance(red), 0.02) << i;
    EXPECT_LE(luminance(blue), luminance(ramp[static_cast<std::size_t>(kDivergingCentre - i + 1)]) + 1e-3) << i;
    EXPECT_LE(luminance(red), luminance(ramp[static_cast<std::size_t>(kDivergingCentre + i - 1)]) + 1e-3) << i;
  }
  EXPECT_LT(luminance(ramp[0]), 0.25);
  EXPECT_LT(luminance(ramp[kDivergingRampSize - 1]), 0.25);

  EXPECT_EQ(diverging_index(0.0, 2.0), kDivergingCentre);
  EXPECT_EQ(diverging_index(-2.0, 2.0), 0);
  EXPECT_EQ(diverging_index(2.0, 2.0), kDivergingRampSize - 1);
  EXPECT_EQ(diverging_index(-9.0, 2.0), 0);
  EXPECT_EQ(diverging_index(9.0, 2.0), kDivergingRampSize - 1);
  EXPECT_EQ(diverging_index(1.0, 2.0), kDivergingCentre + 64);
  EXPECT_EQ(diverging_index(-0.5, 2.0), kDivergingCentre - 32);
  EXPECT_EQ(diverging_index(std::nan(""), 2.0), kDivergingCentre);
  EXPECT_EQ(diverging_index(1.0, 0.0), kDivergingCentre);
  EXPECT_EQ(diverging_index(-std::numeric_limits<double>::infinity(), 1.0), 0);
}

TEST(DivergingRamp, MapErrors) {
  const std::vector<float> v(6, 0.0f);
  DivergingMapOptions o;
  o.range = 0.0;
  std::string msg;
  EXPECT_EQ(code_of([&] { render_diverging_map(3, 2, v, o); }, &msg), ErrorCode::invalid_argument);
  EXPECT_NE(msg.find("positive finite"), std::string::npos) << msg;
  o.range = std::nan("");
  EXPECT_EQ(code_of([&] { render_diverging_map(3, 2, v, o); }), ErrorCode::invalid_argument);
  o.range = 1.0;
  EXPECT_EQ(code_of([&] { render_diverging_map(4, 2, v, o); }), ErrorCode::invalid_argument);
  const DivergingMap small = render_diverging_map(3, 2, v, o);  // too narrow for a legend
  EXPECT_EQ(small.image.height, 2);
}

// A field that is zero on the voxel layer k = 2 (centres on the surface),
// negative below and positive above in the inside-negative convention.
DenseVolume<float> slab_field(const Grid& g, bool inside_negative, double units_per_voxel) {
  DenseVolume<float> f(g);
  for (std::int64_t k = 0; k < g.dims.z; ++k)
    for (std::int64_t j = 0; j < g.dims.y; ++j)
      for (std::int64_t i = 0; i < g.dims.x; ++i) {
        const double d = static_cast<double>(k - 2) * units_per_voxel;
        f.at(i, j, k) = static_cast<float>(inside_negative ? d : -d);
      }
  return f;
}

TEST(SdfSection, ColourInsideBlueZeroWhiteOutsideRedInBothConventions) {
  const Grid g = test::make_grid({20, 18, 7}, {0.0, 0.0, 0.0}, 0.5);
  for (const bool inside_negative : {true, false}) {
    SCOPED_TRACE(inside_negative ? "inside negative" : "inside positive");
    const DenseVolume<float> f = slab_field(g, inside_negative, 0.5);
    const SdfRenderInput in{&f, inside_negative, 0.5, "model units"};
    EXPECT_DOUBLE_EQ(sdf_section_range(in), 2.0);  // |k - 2| <= 4 voxels of 0.5
    const json png = decode_png(sdf_section_png(in, 0, 5, true, {{"voxd:job", "j2"}}));
    ASSERT_EQ(png["width"], 18);
    ASSERT_EQ(png["height"], 7 + kLegendHeight);
    EXPECT_EQ(png["color_type"], 2);
    const auto& ramp = diverging_ramp();
    for (int r = 0; r < 7; ++r)
      for (int c = 0; c < 18; ++c) {
        const Rgb px = pixel(png, c, r);
        const float value = f.at(5, c, r);
        const double inside_negative_value = inside_negative ? value : -value;
        EXPECT_EQ(px, ramp[static_cast<std::size_t>(diverging_index(inside_negative_value, 2.0))]);
        if (r == 2) {
          EXPECT_EQ(px, (Rgb{255, 255, 255})) << "zero is white";
        } else if (r < 2) {
          EXPECT_GT(px.b, px.r + 20) << "inside is blue, row " << r;
        } else {
          EXPECT_GT(px.r, px.b + 20) << "outside is red, row " << r;
        }
      }
    // Row 0 is 2 voxels = 1 model unit inside, half the range: the quarter point of the ramp.
    EXPECT_EQ(pixel(png, 0, 0), ramp[kDivergingCentre - 64]);
    // Legend: the bar from blue (left) to red (right), white in the middle, labels in ink.
    const int bar_row = 7 + kLegendMargin + 1;
    EXPECT_EQ(pixel(png, kLegendMargin, bar_row), ramp[0]);
    EXPECT_EQ(pixel(png, 18 - kLegendMargin - 1, bar_row), ramp[kDivergingRampSize - 1]);
    EXPECT_EQ(pixel(png, 0, bar_row), kLegendBackground);
    int ink = 0;
    for (int y = 7 + kLegendLabelRow; y < 7 + kLegendLabelRow + 5; ++y)
      for (int x = 0; x < 18; ++x) ink += pixel(png, x, y) == kLegendInk;
    EXPECT_GT(ink, 10) << "labels";
    // The left label is the inside end's value: "-2" or "2".
    RgbImage expect_label{18, 5, std::vector<std::uint8_t>(18 * 5 * 3, 255)};
    draw_label(expect_label, kLegendMargin, 0, inside_negative ? "-2" : "2", kLegendInk);
    for (int y = 0; y < 5; ++y)
      for (int x = kLegendMargin; x < kLegendMargin + 7; ++x) {
        const std::uint8_t* e = &expect_label.pixels[(static_cast<std::size_t>(y) * 18 + x) * 3];
        EXPECT_EQ(pixel(png, x, 7 + kLegendLabelRow + y), (Rgb{e[0], e[1], e[2]})) << x << "," << y;
      }
    EXPECT_EQ(png["text"]["voxd:axis"], "x");
    EXPECT_EQ(png["text"]["voxd:index"], "5");
    EXPECT_EQ(png["text"]["voxd:plane"], "2.75 model units (voxel centres)");
    EXPECT_EQ(png["text"]["voxd:unit"], "model units");
    EXPECT_EQ(png["text"]["voxd:range"], "2 model units");
    EXPECT_EQ(png["text"]["voxd:sign"], inside_negative ? "inside negative" : "inside positive");
    EXPECT_EQ(png["text"]["voxd:min"], "-2 model units");
    EXPECT_EQ(png["text"]["voxd:max"], "2 model units");
    EXPECT_EQ(png["text"]["voxd:centre"], "0 = rgb(255,255,255)");
    EXPECT_NE(png["text"]["voxd:legend"].get<std::string>().find("bottom"), std::string::npos);
    EXPECT_EQ(png["text"]["voxd:job"], "j2");
  }
}

TEST(SdfSection, GreyIsTheLinearMapOfTheValue) {
  const Grid g = test::make_grid({6, 5, 7});
  for (const bool inside_negative : {true, false}) {
    DenseVolume<float> f = slab_field(g, inside_negative, 1.0);
    f.at(1, 1, 3) = 0.3f;
    f.at(2, 1, 3) = std::nanf("");
    const SdfRenderInput in{&f, inside_negative, 1.0, "voxel"};
    EXPECT_DOUBLE_EQ(sdf_section_range(in), 4.0);  // NaN skipped
    const json png = decode_png(sdf_section_png(in, 1, 1, false));
    ASSERT_EQ(png["width"], 6);
    ASSERT_EQ(png["height"], 7);
    EXPECT_EQ(png["color_type"], 0);
    const auto pixels = png["pixels"].get<std::vector<int>>();
    for (int r = 0; r < 7; ++r)
      for (int c = 0; c < 6; ++c) {
        const double v = f.at(c, 1, r);
        const int want = std::isnan(v) ? 128 : static_cast<int>(std::lround(127.5 + 127.5 * v / 4.0));
        EXPECT_EQ(pixels[static_cast<std::size_t>(r * 6 + c)], want) << c << "," << r;
      }
    // -range is black, 0 is 128, +range is white; inside dark only for inside negative.
    EXPECT_EQ(pixels[0], inside_negative ? 64 : 191);   // row 0: value -+2
    EXPECT_EQ(pixels[2 * 6], 128);                       // row 2: zero
    EXPECT_EQ(pixels[6 * 6], inside_negative ? 255 : 0);  // row 6: value +-4
    EXPECT_EQ(png["text"]["voxd:unit"], "voxel");
    EXPECT_EQ(png["text"]["voxd:range"], "4 voxel");
    EXPECT_NE(png["text"]["voxd:grey"].get<std::string>().find("127.5"), std::string::npos);
  }
}

TEST(SdfSection, AllZeroFieldIsWhiteAndMidGrey) {
  const Grid g = test::make_grid({16, 3, 2});
  const DenseVolume<float> f(g, 0.0f);
  const SdfRenderInput in{&f, true, 1.0, "voxel"};
  EXPECT_EQ(sdf_section_range(in), 0.0);
  const json colour = decode_png(sdf_section_png(in, 2, 0, true));
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 16; ++c) EXPECT_EQ(pixel(colour, c, r), (Rgb{255, 255, 255}));
  EXPECT_EQ(colour["text"]["voxd:range"], "0 voxel");
  const json grey = decode_png(sdf_section_png(in, 2, 1, false));
  for (const int p : grey["pixels"].get<std::vector<int>>()) EXPECT_EQ(p, 128);
}

TEST(ValueSections, BadPlanesAreInvalidArguments) {
  const DenseVolume<std::uint8_t> bytes(kGrid);
  const DenseVolume<float> floats(kGrid);
  const SdfRenderInput in{&floats, true, 1.0, "voxel"};
  std::string msg;
  for (const int axis : {-1, 3}) {
    EXPECT_EQ(code_of([&] { coverage_section_png(bytes, axis, 0); }, &msg), ErrorCode::invalid_argument);
    EXPECT_EQ(msg, "axis must be 0 (x), 1 (y) or 2 (z), got " + std::to_string(axis));
    EXPECT_EQ(code_of([&] { coverage_section_png(floats, axis, 0); }), ErrorCode::invalid_argument);
    EXPECT_EQ(code_of([&] { sdf_section_png(in, axis, 0, true); }, &msg), ErrorCode::invalid_argument);
    EXPECT_EQ(msg, "axis must be 0 (x), 1 (y) or 2 (z), got " + std::to_string(axis));
  }
  EXPECT_EQ(code_of([&] { coverage_section_png(bytes, 1, 5); }, &msg), ErrorCode::invalid_argument);
  EXPECT_EQ(msg, "section index along y is 5, outside 0..4");
  EXPECT_EQ(code_of([&] { coverage_section_png(floats, 0, -1); }, &msg), ErrorCode::invalid_argument);
  EXPECT_EQ(msg, "section index along x is -1, outside 0..6");
  EXPECT_EQ(code_of([&] { sdf_section_png(in, 2, 4, false); }, &msg), ErrorCode::invalid_argument);
  EXPECT_EQ(msg, "section index along z is 4, outside 0..3");
  EXPECT_EQ(code_of([&] { value_section(floats, 2, 4); }), ErrorCode::invalid_argument);
  EXPECT_EQ(code_of([&] { sdf_section_png(SdfRenderInput{}, 2, 0, true); }, &msg), ErrorCode::invalid_argument);
  EXPECT_EQ(msg, "sdf section: no signed distance field given");
  EXPECT_EQ(code_of([&] { sdf_section_range(SdfRenderInput{}); }), ErrorCode::invalid_argument);
  EXPECT_EQ(code_of([&] { sdf_section_png(SdfRenderInput{&floats, true, -1.0, "voxel"}, 2, 0, true); }, &msg),
            ErrorCode::invalid_argument);
  EXPECT_EQ(msg, "sdf section: units_per_voxel must be a positive finite number, got -1");
}

}  // namespace
}  // namespace voxd
