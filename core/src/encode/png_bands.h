#pragma once
// A PNG written without libpng, its image data compressed in bands of rows
// on every core: libpng filters and deflates a whole image on one thread,
// which for a radiograph of an 8192^3 grid (65 megapixels, 130 MB of
// samples) is most of the request. Each band's rows are filtered and
// deflated apart, primed with the 32 KiB of filtered data before it (as
// pigz does), and ended on a byte boundary (a sync flush), so the bands
// joined in order are one zlib stream, whose checksum is combined from
// theirs. The bands are fixed by the image's size alone, so the bytes are
// the same on any number of threads.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "voxd/byte_sink.h"
#include "voxd/encode/png_image.h"

namespace voxd::encode {

// An image's rows as PNG stores them (big-endian 16-bit samples).
struct PngRows {
  int width = 0;
  int height = 0;
  int bit_depth = 8;
  int colour_type = 0;  // 0 grey, 2 RGB, 6 RGBA
  int pixel_bytes = 1;  // bytes of one pixel: the filters' left neighbour
  std::size_t row_bytes = 0;
  std::vector<const std::uint8_t*> rows;
};

// Filtered bytes (a filter byte a row, then its samples) a band holds: a
// sixteenth of the image, so 16 threads share an image of 1 MiB or more,
// but at least 64 KiB (each band re-filters and primes the 32 KiB before
// it) and at most 256 KiB. Whole rows: the last band fewer.
inline constexpr std::size_t kPngMinBandBytes = std::size_t{64} << 10;
inline constexpr std::size_t kPngMaxBandBytes = std::size_t{256} << 10;
std::size_t png_band_bytes(const PngRows& image);

// Whether an image of these rows is written in bands: from four bands up
// (256 KiB). Smaller ones go through libpng, whose bytes they keep.
bool png_in_bands(const PngRows& image);

// The whole PNG: signature, IHDR, a tEXt chunk for each text (checked by
// the caller), an IDAT chunk a band, IEND. `compression` as for libpng:
// balanced is zlib level 6 and each row's filter chosen as libpng does (the
// least sum of the filtered bytes read as signed), fast is level 1 and the
// Sub filter.
void write_png_in_bands(const PngRows& image, const std::vector<PngText>& text, ByteSink& out,
                        PngCompression compression, int threads);

}  // namespace voxd::encode
