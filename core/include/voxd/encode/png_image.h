#pragma once
// PNG encoding of analysis images (thickness maps, cross-sections) with
// libpng, and large ones in bands of rows on every core with zlib alone.
// Metadata goes in tEXt chunks, which every PNG reader keeps and ignores
// safely: what a pixel value means ("voxd:scale", "voxd:unit") travels with
// the image instead of in a side channel.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "voxd/byte_sink.h"

namespace voxd {

// One tEXt chunk. Keys: 1 to 79 printable Latin-1 characters without leading,
// trailing or double spaces (PNG spec 11.3.4.3); values: no NUL bytes.
struct PngText {
  std::string key;
  std::string value;
};

// What one unit of pixel value is in model units, e.g. {0.125, "mm"} for a
// voxel-count map on a 0.125 mm grid. Written as tEXt "voxd:scale" =
// "1 pixel value = 0.125 mm" and "voxd:unit" = "mm".
struct PngScale {
  double per_value = 1.0;
  std::string unit = "voxel";
};

// The scale as its two tEXt chunks.
std::vector<PngText> scale_text(const PngScale& scale);

// 8-bit RGB image, row-major, 3 bytes per pixel (r, g, b).
struct RgbImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> pixels;
};

// Every writer takes `threads` (0 = every core): an image of 256 KiB of
// rows or more (four bands) is filtered and deflated in bands of rows on
// that many threads (16 bands from 1 MiB), its bytes the same on any number
// (core/src/encode/png_bands.h); smaller ones are written by libpng on the
// calling thread.

// 16-bit greyscale: one pixel per value, row-major (values.size() must be
// width * height). Throws Error(limit_exceeded) when a value exceeds 65535
// (the format cannot hold it; a map of a volume over 65535 voxels long would),
// Error(invalid_argument) for empty or mismatched sizes and bad text.
void write_png_grey16(int width, int height, std::span<const std::uint32_t> values, const PngScale& scale,
                      const std::vector<PngText>& text, ByteSink& out, int threads = 0);

// 8-bit greyscale, e.g. a cross-section (255 filled, 0 empty).
void write_png_grey8(int width, int height, std::span<const std::uint8_t> pixels, const std::vector<PngText>& text,
                     ByteSink& out, int threads = 0);

// How hard libpng compresses: balanced is its default (zlib level 6, the
// best of five filters per row); fast is zlib level 1 with one filter (Sub),
// for bulk output such as a PNG stack, or images redrawn while
// a parameter is dragged: at 512^3 about 2.5 x faster for 12%
// larger files.
enum class PngCompression { balanced, fast };

// 8-bit RGB, e.g. a false-colour thickness map (voxd/encode/colour_map.h).
void write_png_rgb8(const RgbImage& image, const std::vector<PngText>& text, ByteSink& out,
                    PngCompression compression = PngCompression::balanced, int threads = 0);

// 8-bit RGBA, 4 bytes per pixel (r, g, b, a), row-major, straight (not
// premultiplied) alpha, e.g. one layer of a colour volume (voxd/encode/png_stack.h).
void write_png_rgba8(int width, int height, std::span<const std::uint8_t> pixels, const std::vector<PngText>& text,
                     ByteSink& out, PngCompression compression = PngCompression::balanced, int threads = 0);

}  // namespace voxd
