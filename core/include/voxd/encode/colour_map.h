#pragma once
// False-colour rendering of a thickness map: each value through a perceptual
// colour ramp (lightness rises steadily from dark violet through blue, teal
// and green to yellow, like viridis, so equal steps in thickness look like
// equal steps and the map survives greyscale printing and colour-vision
// deficiencies), rays without material in a neutral colour outside the ramp,
// and a legend strip under the map.
#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "voxd/encode/png_image.h"

namespace voxd {

struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
  bool operator==(const Rgb&) const = default;
};

// The 256-entry ramp, index 0 = thinnest.
const std::array<Rgb, 256>& thickness_ramp();

// Colour of pixels whose value is 0 (the ray crosses no material): white,
// lighter than any ramp entry.
inline constexpr Rgb kNoMaterialColour{255, 255, 255};
// Legend: background and tick marks/labels.
inline constexpr Rgb kLegendBackground{255, 255, 255};
inline constexpr Rgb kLegendInk{0, 0, 0};

// Legend strip geometry (rows under the map), drawn when the map is at least
// kLegendMinWidth pixels wide.
inline constexpr int kLegendHeight = 21;
inline constexpr int kLegendMinWidth = 16;
inline constexpr int kLegendMargin = 2;    // columns left and right of the bar, rows above it
inline constexpr int kLegendBarRows = 8;   // the ramp itself
inline constexpr int kLegendTickRows = 3;  // under the bar at 0, 1/4, 1/2, 3/4, 1 of the range
inline constexpr int kLegendLabelRow = kLegendMargin + kLegendBarRows + kLegendTickRows + 1;  // 3x5 digits

struct ColourMapOptions {
  PngScale scale;  // labels and tEXt are value * scale.per_value
  // Values mapped to the ends of the ramp; default: smallest and largest
  // non-zero value. Values outside are clamped to the ends.
  std::optional<std::uint32_t> range_min;
  std::optional<std::uint32_t> range_max;
  bool legend = true;
};

struct ColourMap {
  RgbImage image;              // height = map height (+ kLegendHeight with a legend)
  std::uint32_t range_min = 0;  // the values at ramp index 0 and 255
  std::uint32_t range_max = 0;
  // tEXt chunks describing the image: voxd:scale, voxd:unit, voxd:min,
  // voxd:max (model units), voxd:no_material, voxd:legend.
  std::vector<PngText> text;
};

// Ramp index of `value` in [lo, hi]: round((value - lo) * 255 / (hi - lo)),
// clamped; 255 when lo == hi.
int ramp_index(std::uint32_t value, std::uint32_t lo, std::uint32_t hi);

// Rows are coloured on up to `threads` threads (0: every core); the image
// is the same on any count. Throws Error(invalid_argument) for sizes that do
// not match or a range with min > max.
ColourMap render_thickness_map(int width, int height, std::span<const std::uint32_t> values,
                               const ColourMapOptions& options = {}, int threads = 0);

// Diverging ramp for signed values (a signed distance field section),
// computed like the thickness ramp in OKLab: blue for negative values, white
// (255, 255, 255) exactly at zero, red for positive values. Lightness falls
// linearly with |value| from white to the same lightness at both ends, so the
// two halves are mirror images in brightness and equal steps look equal
// (Moreland 2009's criteria for a cool-warm map, with a white centre).
// kDivergingRampSize entries, index kDivergingCentre = white, 0 = most
// negative (blue), kDivergingRampSize - 1 = most positive (red).
inline constexpr int kDivergingRampSize = 257;
inline constexpr int kDivergingCentre = 128;
const std::array<Rgb, kDivergingRampSize>& diverging_ramp();

// Ramp index of `value` on [-range, range]: kDivergingCentre + round(128 *
// value / range), clamped to the ends; kDivergingCentre for 0, NaN or a range
// that is not positive.
int diverging_index(double value, double range);

struct DivergingMapOptions {
  double range = 1.0;           // values at the ends: -range (blue) and +range (red); must be > 0 and finite
  std::string unit = "voxel";   // the values' unit, for the labels and tEXt
  // The colours follow the opposite sign: positive values blue, negative red
  // (a field that is positive inside stays blue inside). Labels keep the
  // values' own signs, so the left end then reads +range.
  bool positive_blue = false;
  bool legend = true;
};

struct DivergingMap {
  RgbImage image;  // height = map height (+ kLegendHeight with a legend)
  // tEXt: voxd:unit, voxd:min and voxd:max (-range and +range with the
  // unit), voxd:colours (which sign is blue), voxd:centre, voxd:legend.
  std::vector<PngText> text;
};

// Each value in the colour of diverging_index(value, range) (negated with
// positive_blue), NaN in the centre colour; legend strip (the same geometry
// as the thickness legend: bar, ticks at quarters, labels at both ends and
// "0" in the middle where they fit) when the map is at least
// kLegendMinWidth pixels wide. Throws Error(invalid_argument) for sizes that
// do not match or a range that is not a positive finite number.
DivergingMap render_diverging_map(int width, int height, std::span<const float> values,
                                  const DivergingMapOptions& options);

// Writes a legend label at (x, y) (top-left) in the 3x5 pixel font: digits,
// '.', '-', '+', 'e'. Returns the width drawn (4 pixels per character minus
// the last gap). Exposed for tests.
int draw_label(RgbImage& image, int x, int y, std::string_view text, Rgb ink);
int label_width(std::string_view text);

}  // namespace voxd
