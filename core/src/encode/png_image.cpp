// PNG writing through libpng, or for large images in bands on every core
// (png_bands.h). libpng reports errors by longjmp; C++ objects
// must not be skipped by it, so everything with a destructor (rows, strings,
// the text table) is built before setjmp, and the sink's exceptions are
// caught in the write callback, stored, and rethrown after libpng unwinds.
#include "voxd/encode/png_image.h"

#include <png.h>

#include <algorithm>
#include <atomic>
#include <charconv>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <exception>
#include <memory>

#include "encode/png_bands.h"
#include "voxd/encode/number_text.h"
#include "voxd/error.h"
#include "voxd/parallel.h"
#include "voxd/uncleared_vector.h"

namespace voxd {
namespace {

struct WriteContext {
  ByteSink* sink = nullptr;
  std::exception_ptr sink_error;
  char message[256] = {};
};

void on_error(png_structp png, png_const_charp message) {
  auto* ctx = static_cast<WriteContext*>(png_get_error_ptr(png));
  std::snprintf(ctx->message, sizeof ctx->message, "%s", message);
  png_longjmp(png, 1);
}

void on_warning(png_structp, png_const_charp) {}  // inputs are validated before libpng sees them

void on_write(png_structp png, png_bytep data, png_size_t length) {
  auto* ctx = static_cast<WriteContext*>(png_get_io_ptr(png));
  bool failed = false;
  try {
    ctx->sink->write(data, length);
  } catch (...) {
    ctx->sink_error = std::current_exception();
    failed = true;
  }
  if (failed) png_error(png, "the output sink failed");  // outside the catch block: longjmp must not leave it
}

void on_flush(png_structp) {}

void check_text(const std::vector<PngText>& text) {
  for (const PngText& t : text) {
    const std::string& k = t.key;
    bool ok = !k.empty() && k.size() <= 79 && k.front() != ' ' && k.back() != ' ' && k.find("  ") == std::string::npos;
    for (const char c : k) {
      const auto u = static_cast<unsigned char>(c);
      ok = ok && ((u >= 32 && u <= 126) || u >= 161);
    }
    if (!ok) {
      throw Error(ErrorCode::invalid_argument,
                  "PNG text key \"" + k + "\" is not 1 to 79 printable Latin-1 characters without leading, trailing or double spaces");
    }
    if (t.value.find('\0') != std::string::npos) {
      throw Error(ErrorCode::invalid_argument, "PNG text \"" + k + "\" contains a NUL byte");
    }
  }
}

void check_size(int width, int height, std::size_t values, const char* what) {
  if (width < 1 || height < 1) {
    throw Error(ErrorCode::invalid_argument, std::string("a PNG ") + what + " needs at least 1 x 1 pixels, got " +
                                                 std::to_string(width) + " x " + std::to_string(height));
  }
  // libpng refuses images over 1,000,000 pixels per side by default.
  if (width > 1000000 || height > 1000000) {
    throw Error(ErrorCode::limit_exceeded, std::string("a PNG ") + what + " of " + std::to_string(width) + " x " +
                                               std::to_string(height) + " pixels exceeds 1000000 pixels per side");
  }
  if (values != static_cast<std::size_t>(width) * static_cast<std::size_t>(height)) {
    throw Error(ErrorCode::invalid_argument, std::string("PNG ") + what + ": " + std::to_string(values) +
                                                 " pixels given for " + std::to_string(width) + " x " + std::to_string(height));
  }
}

// The only function with setjmp: it holds nothing with a destructor, so the
// longjmp from libpng's error path skips no cleanup. False on a libpng error.
[[gnu::noinline]] bool run_libpng(WriteContext& ctx, int width, int height, int bit_depth, int colour_type,
                                  const png_bytep* rows, png_text* chunks, int chunk_count, PngCompression compression) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &ctx, on_error, on_warning);
  if (png == nullptr) {
    std::snprintf(ctx.message, sizeof ctx.message, "out of memory");
    return false;
  }
  png_infop info = png_create_info_struct(png);
  if (info == nullptr || setjmp(png_jmpbuf(png))) {
    if (info == nullptr) std::snprintf(ctx.message, sizeof ctx.message, "out of memory");
    png_destroy_write_struct(&png, &info);
    return false;
  }
  png_set_write_fn(png, &ctx, on_write, on_flush);
  if (compression == PngCompression::fast) {
    // zlib's fastest level and one filter instead of trying all five per row.
    png_set_compression_level(png, 1);
    png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_SUB);
  }
  png_set_IHDR(png, info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height), bit_depth, colour_type,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  if (chunk_count > 0) png_set_text(png, info, chunks, chunk_count);
  png_write_info(png, info);
  png_write_image(png, const_cast<png_bytepp>(rows));
  png_write_end(png, info);
  png_destroy_write_struct(&png, &info);
  return true;
}

// The one place that chooses the writer: libpng, or bands for an image of
// four bands or more (256 KiB). `rows` are the encoded rows (big-endian samples for
// 16-bit, as PNG stores them).
void encode_png(int width, int height, int bit_depth, int colour_type, const std::vector<png_bytep>& rows,
            const std::vector<PngText>& text, ByteSink& out, PngCompression compression, int threads) {
  check_text(text);
  encode::PngRows image;
  image.width = width;
  image.height = height;
  image.bit_depth = bit_depth;
  image.colour_type = colour_type;
  const int channels = colour_type == PNG_COLOR_TYPE_RGB ? 3 : colour_type == PNG_COLOR_TYPE_RGBA ? 4 : 1;
  image.pixel_bytes = channels * bit_depth / 8;
  image.row_bytes = static_cast<std::size_t>(width) * static_cast<std::size_t>(image.pixel_bytes);
  if (encode::png_in_bands(image)) {
    image.rows.assign(rows.begin(), rows.end());
    encode::write_png_in_bands(image, text, out, compression, threads);
    return;
  }
  std::vector<std::string> keys, values;  // libpng wants non-const char*
  keys.reserve(text.size());
  values.reserve(text.size());
  std::vector<png_text> chunks(text.size());
  for (std::size_t i = 0; i < text.size(); ++i) {
    keys.push_back(text[i].key);
    values.push_back(text[i].value);
    std::memset(&chunks[i], 0, sizeof(png_text));
    chunks[i].compression = PNG_TEXT_COMPRESSION_NONE;
    chunks[i].key = keys.back().data();
    chunks[i].text = values.back().data();
    chunks[i].text_length = values.back().size();
  }

  WriteContext ctx;
  ctx.sink = &out;
  if (!run_libpng(ctx, width, height, bit_depth, colour_type, rows.data(), chunks.data(), static_cast<int>(chunks.size()),
                  compression)) {
    if (ctx.sink_error) std::rethrow_exception(ctx.sink_error);
    throw Error(ErrorCode::io_error, std::string("PNG encoding failed: ") + ctx.message);
  }
}

// libpng takes the rows as non-const but only reads them: png_write_row
// copies each into its own buffer before filtering (no transforms are set),
// so the caller's pixels are written from where they lie, not copied first.
std::vector<png_bytep> row_pointers(const std::uint8_t* bytes, int height, std::size_t stride) {
  std::vector<png_bytep> rows(static_cast<std::size_t>(height));
  for (std::size_t r = 0; r < rows.size(); ++r) rows[r] = const_cast<png_bytep>(bytes + r * stride);
  return rows;
}

}  // namespace

std::vector<PngText> scale_text(const PngScale& scale) {
  return {{"voxd:scale", "1 pixel value = " + number_text(scale.per_value) + " " + scale.unit},
          {"voxd:unit", scale.unit}};
}

void write_png_grey16(int width, int height, std::span<const std::uint32_t> values, const PngScale& scale,
                      const std::vector<PngText>& text, ByteSink& out, int threads) {
  check_size(width, height, values.size(), "16-bit image");
  // Big-endian samples, rows on every thread: a radiograph of an 8192^3
  // grid is 65 megapixels, whose 130 MB are faulted in as they are written
  // (hence not cleared first: an UnclearedVector, as the radiograph's maps).
  // The first pixel over 65535 in row order is the one named, on any number
  // of threads.
  UnclearedVector<std::uint8_t> bytes;
  bytes.resize(values.size() * 2);
  std::atomic<std::size_t> first_over{SIZE_MAX};
  const auto w = static_cast<std::size_t>(width);
  parallel_for(0, height, std::max<std::int64_t>(1, (std::int64_t{1} << 18) / width), threads,
               [&](std::int64_t r0, std::int64_t r1) {
                 for (std::size_t i = static_cast<std::size_t>(r0) * w; i < static_cast<std::size_t>(r1) * w; ++i) {
                   const std::uint32_t v = values[i];
                   if (v > 65535) {
                     std::size_t seen = first_over.load();
                     while (i < seen && !first_over.compare_exchange_weak(seen, i)) {
                     }
                     return;
                   }
                   bytes[2 * i] = static_cast<std::uint8_t>(v >> 8);
                   bytes[2 * i + 1] = static_cast<std::uint8_t>(v);
                 }
               });
  if (const std::size_t i = first_over.load(); i != SIZE_MAX) {
    throw Error(ErrorCode::limit_exceeded,
                "pixel (" + std::to_string(i % w) + ", " + std::to_string(i / w) + ") has value " +
                    std::to_string(values[i]) + ", over 65535, the largest a 16-bit PNG can store");
  }
  std::vector<PngText> all = scale_text(scale);
  all.insert(all.end(), text.begin(), text.end());
  encode_png(width, height, 16, PNG_COLOR_TYPE_GRAY, row_pointers(bytes.data(), height, w * 2), all, out,
         PngCompression::balanced, threads);
  free_on_every_thread(bytes, threads);
}

void write_png_grey8(int width, int height, std::span<const std::uint8_t> pixels, const std::vector<PngText>& text,
                     ByteSink& out, int threads) {
  check_size(width, height, pixels.size(), "8-bit image");
  encode_png(width, height, 8, PNG_COLOR_TYPE_GRAY, row_pointers(pixels.data(), height, static_cast<std::size_t>(width)), text, out,
         PngCompression::balanced, threads);
}

void write_png_rgb8(const RgbImage& image, const std::vector<PngText>& text, ByteSink& out, PngCompression compression,
                    int threads) {
  if (image.pixels.size() % 3 != 0) {
    throw Error(ErrorCode::invalid_argument, "RGB image has " + std::to_string(image.pixels.size()) + " bytes, not a multiple of 3");
  }
  check_size(image.width, image.height, image.pixels.size() / 3, "RGB image");
  encode_png(image.width, image.height, 8, PNG_COLOR_TYPE_RGB,
         row_pointers(image.pixels.data(), image.height, static_cast<std::size_t>(image.width) * 3), text, out, compression, threads);
}

void write_png_rgba8(int width, int height, std::span<const std::uint8_t> pixels, const std::vector<PngText>& text,
                     ByteSink& out, PngCompression compression, int threads) {
  if (pixels.size() % 4 != 0) {
    throw Error(ErrorCode::invalid_argument, "RGBA image has " + std::to_string(pixels.size()) + " bytes, not a multiple of 4");
  }
  check_size(width, height, pixels.size() / 4, "RGBA image");
  encode_png(width, height, 8, PNG_COLOR_TYPE_RGBA, row_pointers(pixels.data(), height, static_cast<std::size_t>(width) * 4), text, out,
         compression, threads);
}

}  // namespace voxd
