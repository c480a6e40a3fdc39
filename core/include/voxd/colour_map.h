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
#include <string_view>
#include <vector>

#include "voxd/png_image.h"

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

// Throws Error(invalid_argument) for sizes that do not match or a range with
// min > max.
ColourMap render_thickness_map(int width, int height, std::span<const std::uint32_t> values,
                               const ColourMapOptions& options = {});

// Writes a legend label at (x, y) (top-left) in the 3x5 pixel font: digits,
// '.', '-', '+', 'e'. Returns the width drawn (4 pixels per character minus
// the last gap). Exposed for tests.
int draw_label(RgbImage& image, int x, int y, std::string_view text, Rgb ink);
int label_width(std::string_view text);

}  // namespace voxd
