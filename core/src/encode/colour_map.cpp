// The thickness ramp is computed, not copied: 256 colours along a path in
// OKLab (Ottosson 2020), a space where lightness L and perceived colour
// difference are close to Euclidean. L rises linearly, so the ramp is
// monotone in brightness; the hue turns from violet (305 deg) through blue,
// teal and green to yellow (105 deg); chroma is reduced only as far as needed
// to stay inside sRGB, which keeps L exact.
#include "voxd/encode/colour_map.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <string>

#include "voxd/error.h"
#include "voxd/parallel.h"

namespace voxd {
namespace {

struct LinearRgb {
  double r, g, b;
};

// OKLab -> linear sRGB (Ottosson's published matrices).
LinearRgb oklab_to_linear(double L, double a, double b) {
  const double l_ = L + 0.3963377774 * a + 0.2158037573 * b;
  const double m_ = L - 0.1055613458 * a - 0.0638541728 * b;
  const double s_ = L - 0.0894841775 * a - 1.2914855480 * b;
  const double l = l_ * l_ * l_, m = m_ * m_ * m_, s = s_ * s_ * s_;
  return {4.0767416621 * l - 3.3077115913 * m + 0.2309699292 * s,
          -1.2684380046 * l + 2.6097574011 * m - 0.3413193965 * s,
          -0.0041960863 * l - 0.7034186147 * m + 1.7076147010 * s};
}

bool in_gamut(const LinearRgb& c) {
  constexpr double eps = 1e-9;
  return c.r >= -eps && c.r <= 1 + eps && c.g >= -eps && c.g <= 1 + eps && c.b >= -eps && c.b <= 1 + eps;
}

std::uint8_t to_srgb8(double linear) {
  const double v = std::clamp(linear, 0.0, 1.0);
  const double e = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
  return static_cast<std::uint8_t>(std::lround(e * 255.0));
}

// The sRGB colour of OKLCh (L, chroma, hue in radians), with the chroma cut
// to the largest that sRGB holds (bisected; chroma 0, grey, always fits for
// L <= 1), so every ramp step keeps its lightness and hue.
Rgb oklch_in_gamut(double L, double chroma, double hue) {
  if (!in_gamut(oklab_to_linear(L, chroma * std::cos(hue), chroma * std::sin(hue)))) {
    double lo = 0.0, hi = chroma;
    for (int step = 0; step < 40; ++step) {
      const double mid = 0.5 * (lo + hi);
      (in_gamut(oklab_to_linear(L, mid * std::cos(hue), mid * std::sin(hue))) ? lo : hi) = mid;
    }
    chroma = lo;
  }
  const LinearRgb c = oklab_to_linear(L, chroma * std::cos(hue), chroma * std::sin(hue));
  return {to_srgb8(c.r), to_srgb8(c.g), to_srgb8(c.b)};
}

std::array<Rgb, 256> build_ramp() {
  std::array<Rgb, 256> ramp{};
  for (int i = 0; i < 256; ++i) {
    const double t = i / 255.0;
    const double L = 0.30 + 0.62 * t;
    const double hue = (305.0 - 200.0 * t) * std::numbers::pi / 180.0;
    // Wanted chroma: vivid at both ends, softer through teal (as in viridis).
    const double chroma = 0.13 + 0.05 * t * t - 0.04 * std::sin(std::numbers::pi * t);
    ramp[static_cast<std::size_t>(i)] = oklch_in_gamut(L, chroma, hue);
  }
  return ramp;
}

// The diverging ramp: lightness L = 1 - 0.5 |t| (white at t = 0, L = 0.5 at
// both ends), hue blue (265 deg) for t < 0 and red (25 deg) for t > 0, the
// wanted chroma 0.19 |t|^0.75 (colour comes in quickly off white) reduced
// only as far as sRGB requires, as in build_ramp().
std::array<Rgb, kDivergingRampSize> build_diverging_ramp() {
  std::array<Rgb, kDivergingRampSize> ramp{};
  for (int i = 0; i < kDivergingRampSize; ++i) {
    const double t = static_cast<double>(i - kDivergingCentre) / kDivergingCentre;
    const double s = std::abs(t);
    const double L = 1.0 - 0.5 * s;
    const double hue = (t < 0 ? 265.0 : 25.0) * std::numbers::pi / 180.0;
    ramp[static_cast<std::size_t>(i)] = oklch_in_gamut(L, 0.19 * std::pow(s, 0.75), hue);
  }
  ramp[kDivergingCentre] = {255, 255, 255};  // OKLab's white is 1 - 1e-10 off in the published matrices
  return ramp;
}

// 3x5 pixel glyphs, one 3-bit row per nibble, top row first, bit 2 = left column.
struct Glyph {
  char c;
  std::uint8_t rows[5];
};
constexpr Glyph kFont[] = {
    {'0', {7, 5, 5, 5, 7}}, {'1', {2, 6, 2, 2, 7}}, {'2', {7, 1, 7, 4, 7}}, {'3', {7, 1, 7, 1, 7}},
    {'4', {5, 5, 7, 1, 1}}, {'5', {7, 4, 7, 1, 7}}, {'6', {7, 4, 7, 5, 7}}, {'7', {7, 1, 1, 1, 1}},
    {'8', {7, 5, 7, 5, 7}}, {'9', {7, 5, 7, 1, 7}}, {'.', {0, 0, 0, 0, 2}}, {'-', {0, 0, 7, 0, 0}},
    {'+', {0, 2, 7, 2, 0}}, {'e', {7, 4, 7, 4, 7}},
};

void put(RgbImage& image, int x, int y, Rgb c) {
  if (x < 0 || y < 0 || x >= image.width || y >= image.height) return;
  std::uint8_t* p = image.pixels.data() + (static_cast<std::size_t>(y) * static_cast<std::size_t>(image.width) + static_cast<std::size_t>(x)) * 3;
  p[0] = c.r;
  p[1] = c.g;
  p[2] = c.b;
}

std::string label(double value) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", value);  // 4 significant digits are plenty for a legend
  return buf;
}

std::string format_value(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// The legend strip under a map of `height` rows (img already has the
// kLegendHeight rows): white background, the bar coloured by colour_at(x,
// bar_w) for bar columns x = 0..bar_w, ticks at quarters, `left` and `right`
// labels at the ends when both fit, `centre` under the middle tick when it
// fits between them too.
template <class ColourAt>
void draw_legend(RgbImage& img, int height, ColourAt colour_at, const std::string& left, const std::string& right,
                 const std::string& centre) {
  const int width = img.width;
  for (int y = height; y < img.height; ++y) {
    for (int x = 0; x < width; ++x) put(img, x, y, kLegendBackground);
  }
  const int x0 = kLegendMargin, x1 = width - kLegendMargin - 1;  // bar columns, inclusive
  const int bar_w = x1 - x0;
  const int bar_top = height + kLegendMargin;
  for (int x = x0; x <= x1; ++x) {
    const Rgb c = colour_at(x - x0, bar_w);
    for (int y = bar_top; y < bar_top + kLegendBarRows; ++y) put(img, x, y, c);
  }
  for (int q = 0; q <= 4; ++q) {
    const int x = x0 + (q * bar_w * 2 + 4) / 8;  // round(q/4 * bar_w)
    for (int y = bar_top + kLegendBarRows; y < bar_top + kLegendBarRows + kLegendTickRows; ++y) put(img, x, y, kLegendInk);
  }
  if (label_width(left) + label_width(right) + 4 <= bar_w + 1) {  // both fit with a gap
    const int y = height + kLegendLabelRow;
    draw_label(img, x0, y, left, kLegendInk);
    const int right_x = x1 + 1 - label_width(right);
    draw_label(img, right_x, y, right, kLegendInk);
    const int centre_x = x0 + (2 * bar_w * 2 + 4) / 8 - label_width(centre) / 2;
    if (!centre.empty() && centre_x >= x0 + label_width(left) + 2 && centre_x + label_width(centre) + 2 <= right_x) {
      draw_label(img, centre_x, y, centre, kLegendInk);
    }
  }
}

}  // namespace

const std::array<Rgb, 256>& thickness_ramp() {
  static const std::array<Rgb, 256> ramp = build_ramp();
  return ramp;
}

int ramp_index(std::uint32_t value, std::uint32_t lo, std::uint32_t hi) {
  if (hi <= lo) return 255;
  if (value <= lo) return 0;
  if (value >= hi) return 255;
  const std::uint64_t span = hi - lo;
  return static_cast<int>(((std::uint64_t{value} - lo) * 255 * 2 + span) / (2 * span));  // round half up
}

int label_width(std::string_view text) { return text.empty() ? 0 : static_cast<int>(text.size()) * 4 - 1; }

int draw_label(RgbImage& image, int x, int y, std::string_view text, Rgb ink) {
  int cx = x;
  for (const char ch : text) {
    for (const Glyph& g : kFont) {
      if (g.c != ch) continue;
      for (int r = 0; r < 5; ++r) {
        for (int c = 0; c < 3; ++c) {
          if ((g.rows[r] >> (2 - c)) & 1) put(image, cx + c, y + r, ink);
        }
      }
    }
    cx += 4;
  }
  return label_width(text);
}

ColourMap render_thickness_map(int width, int height, std::span<const std::uint32_t> values,
                               const ColourMapOptions& options, int threads) {
  if (width < 0 || height < 0 || values.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height)) {
    throw Error(ErrorCode::invalid_argument, "thickness map: " + std::to_string(values.size()) + " values given for " +
                                                 std::to_string(width) + " x " + std::to_string(height) + " pixels");
  }
  // Each pixel's colour is its own value's, and a range is a minimum and a
  // maximum, which no order of taking changes: the rows go to any thread.
  constexpr std::int64_t kRowsAPiece = 64;
  const auto row_pixels = static_cast<std::size_t>(width);
  std::uint32_t lo = 0, hi = 0;
  if (!options.range_min || !options.range_max) {
    struct Range {
      std::uint32_t lo = std::numeric_limits<std::uint32_t>::max(), hi = 0;
    };
    std::vector<Range> pieces(static_cast<std::size_t>((height + kRowsAPiece - 1) / kRowsAPiece));
    parallel_for(0, height, kRowsAPiece, threads, [&](std::int64_t r0, std::int64_t r1) {
      Range& r = pieces[static_cast<std::size_t>(r0 / kRowsAPiece)];
      for (std::size_t p = static_cast<std::size_t>(r0) * row_pixels; p < static_cast<std::size_t>(r1) * row_pixels; ++p) {
        if (values[p] == 0) continue;
        r.lo = std::min(r.lo, values[p]);
        r.hi = std::max(r.hi, values[p]);
      }
    });
    Range all;
    for (const Range& r : pieces) {
      all.lo = std::min(all.lo, r.lo);
      all.hi = std::max(all.hi, r.hi);
    }
    if (all.hi > 0) {  // some value is not 0; else both stay 0
      lo = all.lo;
      hi = all.hi;
    }
  }
  lo = options.range_min.value_or(lo);
  hi = options.range_max.value_or(hi);
  if (lo > hi) {
    throw Error(ErrorCode::invalid_argument, "thickness map range: min " + std::to_string(lo) + " is over max " + std::to_string(hi));
  }
  const bool legend = options.legend && width >= kLegendMinWidth;
  ColourMap out;
  out.range_min = lo;
  out.range_max = hi;
  RgbImage& img = out.image;
  img.width = width;
  img.height = height + (legend ? kLegendHeight : 0);
  img.pixels.resize(static_cast<std::size_t>(img.width) * static_cast<std::size_t>(img.height) * 3);
  const auto& ramp = thickness_ramp();
  parallel_for(0, height, kRowsAPiece, threads, [&](std::int64_t r0, std::int64_t r1) {
    for (std::size_t p = static_cast<std::size_t>(r0) * row_pixels; p < static_cast<std::size_t>(r1) * row_pixels; ++p) {
      const Rgb c = values[p] == 0 ? kNoMaterialColour : ramp[static_cast<std::size_t>(ramp_index(values[p], lo, hi))];
      img.pixels[3 * p] = c.r;
      img.pixels[3 * p + 1] = c.g;
      img.pixels[3 * p + 2] = c.b;
    }
  });
  const double k = options.scale.per_value;
  out.text = scale_text(options.scale);
  out.text.push_back({"voxd:min", format_value(lo * k) + " " + options.scale.unit});
  out.text.push_back({"voxd:max", format_value(hi * k) + " " + options.scale.unit});
  out.text.push_back({"voxd:no_material", "rgb(255,255,255)"});
  if (!legend) {
    out.text.push_back({"voxd:legend", "none"});
    return out;
  }
  out.text.push_back({"voxd:legend", "bottom " + std::to_string(kLegendHeight) +
                                         " rows: colour ramp from voxd:min (left) to voxd:max (right), ticks at quarters"});
  draw_legend(img, height, [&](int x, int bar_w) { return ramp[static_cast<std::size_t>((x * 255 * 2 + bar_w) / (2 * bar_w))]; },
              label(lo * k), label(hi * k), "");
  return out;
}

const std::array<Rgb, kDivergingRampSize>& diverging_ramp() {
  static const std::array<Rgb, kDivergingRampSize> ramp = build_diverging_ramp();
  return ramp;
}

int diverging_index(double value, double range) {
  if (!(range > 0.0) || !(value == value)) return kDivergingCentre;
  const double t = std::clamp(value / range, -1.0, 1.0);  // also clamps +-inf and a range of +inf (t = 0)
  return kDivergingCentre + static_cast<int>(std::lround(t * kDivergingCentre));
}

DivergingMap render_diverging_map(int width, int height, std::span<const float> values,
                                  const DivergingMapOptions& options) {
  if (width < 0 || height < 0 || values.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height)) {
    throw Error(ErrorCode::invalid_argument, "diverging map: " + std::to_string(values.size()) + " values given for " +
                                                 std::to_string(width) + " x " + std::to_string(height) + " pixels");
  }
  const double range = options.range;
  if (!(range > 0.0) || !std::isfinite(range)) {
    throw Error(ErrorCode::invalid_argument, "diverging map range must be a positive finite number, got " + format_value(range));
  }
  const bool legend = options.legend && width >= kLegendMinWidth;
  DivergingMap out;
  RgbImage& img = out.image;
  img.width = width;
  img.height = height + (legend ? kLegendHeight : 0);
  img.pixels.resize(static_cast<std::size_t>(img.width) * static_cast<std::size_t>(img.height) * 3);
  const auto& ramp = diverging_ramp();
  const double sign = options.positive_blue ? -1.0 : 1.0;
  for (std::size_t p = 0; p < values.size(); ++p) {
    const Rgb c = ramp[static_cast<std::size_t>(diverging_index(sign * static_cast<double>(values[p]), range))];
    img.pixels[3 * p] = c.r;
    img.pixels[3 * p + 1] = c.g;
    img.pixels[3 * p + 2] = c.b;
  }
  const std::string& unit = options.unit;
  out.text.push_back({"voxd:unit", unit});
  out.text.push_back({"voxd:min", format_value(-range) + " " + unit});
  out.text.push_back({"voxd:max", format_value(range) + " " + unit});
  out.text.push_back({"voxd:colours", options.positive_blue ? "diverging: positive blue, 0 white, negative red"
                                                            : "diverging: negative blue, 0 white, positive red"});
  out.text.push_back({"voxd:centre", "0 = rgb(255,255,255)"});
  if (!legend) {
    out.text.push_back({"voxd:legend", "none"});
    return out;
  }
  out.text.push_back({"voxd:legend", "bottom " + std::to_string(kLegendHeight) + " rows: colour ramp from " +
                                         format_value(-sign * range) + " (left, blue) through 0 (white) to " +
                                         format_value(sign * range) + " (right, red) " + unit + ", ticks at quarters"});
  draw_legend(img, height,
              [&](int x, int bar_w) {
                return ramp[static_cast<std::size_t>((x * (kDivergingRampSize - 1) * 2 + bar_w) / (2 * bar_w))];
              },
              label(-sign * range), label(sign * range), "0");
  return out;
}

}  // namespace voxd
