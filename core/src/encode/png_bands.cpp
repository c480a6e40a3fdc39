#include "encode/png_bands.h"

#include <zlib.h>

#include <algorithm>
#include <array>
#include <cstdlib>
#include <cstring>
#include <new>
#include <span>
#include <string>

#include "encode/ordered_pipeline.h"
#include "voxd/error.h"
#include "voxd/parallel.h"

namespace voxd::encode {
namespace {

constexpr std::size_t kWindow = 32768;  // deflate's reach back: a band's dictionary

std::array<std::uint8_t, 4> big_endian(std::uint32_t v) {
  return {static_cast<std::uint8_t>(v >> 24), static_cast<std::uint8_t>(v >> 16), static_cast<std::uint8_t>(v >> 8),
          static_cast<std::uint8_t>(v)};
}

// A chunk from its pieces: length, type, the pieces, the CRC of type and
// pieces.
void write_chunk(ByteSink& out, const char* type, std::initializer_list<std::span<const std::uint8_t>> pieces) {
  std::size_t length = 0;
  for (const auto& p : pieces) length += p.size();
  if (length > 0x7fffffffu) throw Error(ErrorCode::limit_exceeded, "a PNG chunk over 2^31 - 1 bytes");
  const auto* type_bytes = reinterpret_cast<const std::uint8_t*>(type);
  uLong crc = crc32(0L, type_bytes, 4);
  for (const auto& p : pieces) crc = crc32_z(crc, p.data(), p.size());
  out.write(big_endian(static_cast<std::uint32_t>(length)));
  out.write(std::span<const std::uint8_t>(type_bytes, 4));
  for (const auto& p : pieces) out.write(p);
  out.write(big_endian(static_cast<std::uint32_t>(crc)));
}

std::int64_t rows_per_band(const PngRows& image) {
  return std::max<std::int64_t>(1, static_cast<std::int64_t>(png_band_bytes(image) / (image.row_bytes + 1)));
}

int paeth(int a, int b, int c) {
  const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
  if (pa <= pb && pa <= pc) return a;
  return pb <= pc ? b : c;
}

// Row r filtered by `type` into out (row_bytes); the row above the first is
// zeros, as a decoder takes it.
void apply_filter(const PngRows& image, std::int64_t r, int type, const std::uint8_t* zeros, std::uint8_t* out) {
  const std::uint8_t* x = image.rows[static_cast<std::size_t>(r)];
  const std::uint8_t* b = r > 0 ? image.rows[static_cast<std::size_t>(r - 1)] : zeros;
  const std::size_t n = image.row_bytes, bpp = static_cast<std::size_t>(image.pixel_bytes);
  switch (type) {
    case 0: std::memcpy(out, x, n); break;
    case 1:
      for (std::size_t i = 0; i < n; ++i) out[i] = static_cast<std::uint8_t>(x[i] - (i >= bpp ? x[i - bpp] : 0));
      break;
    case 2:
      for (std::size_t i = 0; i < n; ++i) out[i] = static_cast<std::uint8_t>(x[i] - b[i]);
      break;
    case 3:
      for (std::size_t i = 0; i < n; ++i) out[i] = static_cast<std::uint8_t>(x[i] - (((i >= bpp ? x[i - bpp] : 0) + b[i]) >> 1));
      break;
    default:
      for (std::size_t i = 0; i < n; ++i)
        out[i] = static_cast<std::uint8_t>(
            x[i] - paeth(i >= bpp ? x[i - bpp] : 0, b[i], i >= bpp ? b[i - bpp] : 0));
      break;
  }
}

// libpng's choice of filter: the least sum of the filtered bytes read as
// signed (their distance from zero), the first of the five on a tie.
std::uint64_t signed_sum(const std::uint8_t* bytes, std::size_t n) {
  std::uint64_t sum = 0;
  for (std::size_t i = 0; i < n; ++i) sum += bytes[i] < 128 ? bytes[i] : 256u - bytes[i];
  return sum;
}

// Rows [r0, r1) filtered, a filter byte before each, appended to `out`.
void filter_rows(const PngRows& image, std::int64_t r0, std::int64_t r1, PngCompression compression,
                 std::vector<std::uint8_t>& out) {
  const std::size_t n = image.row_bytes;
  const std::vector<std::uint8_t> zeros(n, 0);
  std::vector<std::uint8_t> trial(compression == PngCompression::fast ? 0 : n);
  for (std::int64_t r = r0; r < r1; ++r) {
    const std::size_t at = out.size();
    out.resize(at + 1 + n);
    std::uint8_t* row = out.data() + at + 1;
    int chosen = 1;  // fast: Sub
    if (compression != PngCompression::fast) {
      std::uint64_t best = UINT64_MAX;
      for (int type = 0; type < 5; ++type) {
        apply_filter(image, r, type, zeros.data(), trial.data());
        const std::uint64_t sum = signed_sum(trial.data(), n);
        if (sum < best) {
          best = sum;
          chosen = type;
          std::memcpy(row, trial.data(), n);
        }
      }
    } else {
      apply_filter(image, r, chosen, zeros.data(), row);
    }
    out[at] = static_cast<std::uint8_t>(chosen);
  }
}

struct Band {
  std::vector<std::uint8_t> filtered, dictionary, deflated;
  uLong adler = 1;
};

// Band b's rows filtered and deflated: primed with the filtered bytes just
// before it, ended by a sync flush (the last band by the stream's end).
void deflate_band(const PngRows& image, std::int64_t b, std::int64_t bands, PngCompression compression, Band& band) {
  const std::int64_t per_band = rows_per_band(image);
  const std::int64_t r0 = b * per_band, r1 = std::min<std::int64_t>(image.height, r0 + per_band);
  band.filtered.clear();
  filter_rows(image, r0, r1, compression, band.filtered);
  band.adler = adler32_z(adler32(0L, Z_NULL, 0), band.filtered.data(), band.filtered.size());
  band.dictionary.clear();
  if (b > 0) {
    const auto before = static_cast<std::int64_t>((kWindow + image.row_bytes) / (image.row_bytes + 1));
    filter_rows(image, std::max<std::int64_t>(0, r0 - before), r0, compression, band.dictionary);
    if (band.dictionary.size() > kWindow)
      band.dictionary.erase(band.dictionary.begin(),
                            band.dictionary.end() - static_cast<std::ptrdiff_t>(kWindow));
  }

  z_stream z{};
  const int level = compression == PngCompression::fast ? 1 : 6;
  // Raw deflate (no zlib header a band), libpng's memory level and strategy.
  if (deflateInit2(&z, level, Z_DEFLATED, -15, 8, Z_FILTERED) != Z_OK) throw std::bad_alloc();
  struct End {
    z_stream* z;
    ~End() { deflateEnd(z); }
  } end{&z};
  if (!band.dictionary.empty() &&
      deflateSetDictionary(&z, band.dictionary.data(), static_cast<uInt>(band.dictionary.size())) != Z_OK)
    throw Error(ErrorCode::io_error, "PNG encoding failed: zlib refused a band's dictionary");
  const bool last = b + 1 == bands;
  band.deflated.resize(deflateBound(&z, static_cast<uLong>(band.filtered.size())) + 64);
  z.next_in = band.filtered.data();
  z.avail_in = static_cast<uInt>(band.filtered.size());
  std::size_t written = 0;
  for (;;) {
    z.next_out = band.deflated.data() + written;
    z.avail_out = static_cast<uInt>(band.deflated.size() - written);
    const int ret = deflate(&z, last ? Z_FINISH : Z_SYNC_FLUSH);
    if (ret == Z_STREAM_ERROR) throw Error(ErrorCode::io_error, "PNG encoding failed: zlib stream error");
    written = band.deflated.size() - z.avail_out;
    if (last ? ret == Z_STREAM_END : z.avail_in == 0 && z.avail_out > 0) break;
    band.deflated.resize(band.deflated.size() * 2);
  }
  band.deflated.resize(written);
}

}  // namespace

std::size_t png_band_bytes(const PngRows& image) {
  const std::size_t filtered = static_cast<std::size_t>(image.height) * (image.row_bytes + 1);
  return std::clamp(filtered / 16, kPngMinBandBytes, kPngMaxBandBytes);
}

bool png_in_bands(const PngRows& image) {
  const std::int64_t per_band = rows_per_band(image);
  return (image.height + per_band - 1) / per_band >= 4;
}

void write_png_in_bands(const PngRows& image, const std::vector<PngText>& text, ByteSink& out,
                        PngCompression compression, int threads) {
  static constexpr std::uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  out.write(std::span<const std::uint8_t>(kSignature));
  std::array<std::uint8_t, 13> header{};
  const auto w = big_endian(static_cast<std::uint32_t>(image.width));
  const auto h = big_endian(static_cast<std::uint32_t>(image.height));
  std::copy(w.begin(), w.end(), header.begin());
  std::copy(h.begin(), h.end(), header.begin() + 4);
  header[8] = static_cast<std::uint8_t>(image.bit_depth);
  header[9] = static_cast<std::uint8_t>(image.colour_type);  // compression, filter method, interlace: 0
  write_chunk(out, "IHDR", {header});
  for (const PngText& t : text) {
    static constexpr std::uint8_t kNul[1] = {0};
    write_chunk(out, "tEXt",
                {std::span(reinterpret_cast<const std::uint8_t*>(t.key.data()), t.key.size()), kNul,
                 std::span(reinterpret_cast<const std::uint8_t*>(t.value.data()), t.value.size())});
  }

  const std::int64_t per_band = rows_per_band(image);
  const std::int64_t bands = (image.height + per_band - 1) / per_band;
  const int n = threads > 0 ? threads : default_thread_count();
  std::vector<Band> slots(static_cast<std::size_t>(2 * n));
  // zlib's header: deflate with a 32 KiB window, the level's flag, and the
  // check bits that make it a multiple of 31.
  const std::uint8_t cmf = 0x78;
  std::uint8_t flg = compression == PngCompression::fast ? 0x00 : 0x80;
  flg = static_cast<std::uint8_t>(flg + (31 - (cmf * 256 + flg) % 31) % 31);
  const std::uint8_t zlib_header[2] = {cmf, flg};
  uLong adler = 1;
  run_ordered_pipeline(
      bands, n, slots.size(),
      [&](std::int64_t b, std::size_t slot) { deflate_band(image, b, bands, compression, slots[slot]); },
      [&](std::int64_t b, std::size_t slot) {
        const Band& band = slots[slot];
        adler = b == 0 ? band.adler : adler32_combine(adler, band.adler, static_cast<z_off_t>(band.filtered.size()));
        const auto check = big_endian(static_cast<std::uint32_t>(adler));
        write_chunk(out, "IDAT",
                    {std::span<const std::uint8_t>(zlib_header, b == 0 ? 2 : 0), band.deflated,
                     std::span<const std::uint8_t>(check.data(), b + 1 == bands ? 4 : 0)});
      });
  write_chunk(out, "IEND", {});
}

}  // namespace voxd::encode
