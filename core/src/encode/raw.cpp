// Headerless raw volumes, x fastest then y then z: one byte per voxel (0/1) or
// a continuous bit stream (voxel n is bit n % 8 of byte n / 8, no row padding).
#include <algorithm>
#include <array>
#include <cstring>
#include <string>

#include "encode/bit_packer.h"
#include "encode/byte_buffer.h"
#include "encode/volume_checks.h"
#include "voxd/encode/volume_format.h"

namespace voxd {
namespace {

using encode::ByteBuffer;

// Sink writes happen at row boundaries once this much is buffered, so even a
// 65536 x 65536 slab streams through a small buffer.
constexpr std::size_t kFlushBytes = std::size_t{1} << 20;

// The 8 bytes (0 or 1) that one byte of packed bits expands to.
constexpr std::array<std::array<std::uint8_t, 8>, 256> make_byte_expansion() {
  std::array<std::array<std::uint8_t, 8>, 256> table{};
  for (int v = 0; v < 256; ++v)
    for (int t = 0; t < 8; ++t) table[v][t] = static_cast<std::uint8_t>((v >> t) & 1);
  return table;
}
constexpr auto kByteExpansion = make_byte_expansion();

void write_bytes(const BitVolume& volume, ByteSink& sink) {
  const std::int64_t nx = volume.grid().dims.x;
  ByteBuffer out;
  std::uint8_t row_bytes[64];
  for (std::int64_t k = 0; k < volume.grid().dims.z; ++k) {
    for (std::int64_t j = 0; j < volume.grid().dims.y; ++j) {
      const std::uint64_t* row = volume.row(j, k);
      for (std::int64_t i = 0; i < nx; i += 64) {
        const std::uint64_t word = row[i >> 6];
        for (int b = 0; b < 8; ++b) std::memcpy(row_bytes + 8 * b, kByteExpansion[(word >> (8 * b)) & 0xff].data(), 8);
        out.put_bytes(row_bytes, static_cast<std::size_t>(std::min<std::int64_t>(64, nx - i)));
      }
      if (out.size() >= kFlushBytes) {
        sink.write(out.bytes());
        out.reset();
      }
    }
  }
  sink.write(out.bytes());
}

void write_bits(const BitVolume& volume, ByteSink& sink) {
  encode::BitPacker packer;
  encode::pack_raw_bits(volume, packer, sink);
  packer.flush(sink, true);
}

void check_grid(const Grid& grid) {
  for (int a = 0; a < 3; ++a)
    if (grid.dims[a] < 1 || grid.dims[a] > kMaxGridDim)
      throw Error(ErrorCode::invalid_argument, "raw reader: grid dims along " + std::string(1, "xyz"[a]) +
                                                   " is " + std::to_string(grid.dims[a]) +
                                                   "; it must be between 1 and " + std::to_string(kMaxGridDim));
}

void check_size(std::size_t actual, std::uint64_t expected, const char* packing) {
  if (actual < expected)
    throw Error(ErrorCode::truncated_input, "raw " + std::string(packing) + " data has " + std::to_string(actual) +
                                                " bytes; the grid needs " + std::to_string(expected));
  if (actual > expected)
    throw Error(ErrorCode::malformed_input, "raw " + std::string(packing) + " data has " + std::to_string(actual) +
                                                " bytes; the grid needs only " + std::to_string(expected));
}

void read_bytes(std::span<const std::uint8_t> data, BitVolume& volume) {
  const std::int64_t nx = volume.grid().dims.x;
  const std::uint8_t* src = data.data();
  for (std::int64_t k = 0; k < volume.grid().dims.z; ++k) {
    for (std::int64_t j = 0; j < volume.grid().dims.y; ++j) {
      std::uint64_t* row = volume.row(j, k);
      std::uint8_t seen = 0;
      for (std::int64_t i = 0; i < nx; ++i) {
        seen |= src[i];
        row[i >> 6] |= static_cast<std::uint64_t>(src[i] & 1) << (i & 63);
      }
      if (seen > 1) {
        const auto bad = static_cast<std::size_t>(std::find_if(src, src + nx, [](std::uint8_t b) { return b > 1; }) -
                                                  data.data());
        throw Error(ErrorCode::malformed_input, "raw bytes data: byte " + std::to_string(bad) + " is " +
                                                    std::to_string(data[bad]) + "; voxels must be 0 or 1");
      }
      src += nx;
    }
  }
}

// n bits (1..64) of a little-endian bit stream from bit `position`; the
// caller guarantees they lie inside `data`.
std::uint64_t load_bits(std::span<const std::uint8_t> data, std::uint64_t position, int n) {
  const auto first = static_cast<std::size_t>(position >> 3);
  const int shift = static_cast<int>(position & 7);
  const std::size_t bytes = std::min<std::size_t>(static_cast<std::size_t>(shift + n + 7) / 8, data.size() - first);
  std::uint64_t low = 0;
  for (std::size_t b = 0; b < std::min<std::size_t>(bytes, 8); ++b) low |= static_cast<std::uint64_t>(data[first + b]) << (8 * b);
  std::uint64_t v = low >> shift;
  if (bytes == 9) v |= static_cast<std::uint64_t>(data[first + 8]) << (64 - shift);
  return n == 64 ? v : v & ((std::uint64_t{1} << n) - 1);
}

void read_bits(std::span<const std::uint8_t> data, BitVolume& volume) {
  const std::int64_t nx = volume.grid().dims.x;
  const std::uint64_t total = volume.grid().voxel_count();
  if (const int tail = static_cast<int>(total & 7); tail != 0 && (data.back() >> tail) != 0)
    throw Error(ErrorCode::malformed_input, "raw bits data: the padding bits after the last voxel in the last "
                                            "byte must be 0");
  std::uint64_t position = 0;
  for (std::int64_t k = 0; k < volume.grid().dims.z; ++k) {
    for (std::int64_t j = 0; j < volume.grid().dims.y; ++j) {
      std::uint64_t* row = volume.row(j, k);
      for (std::int64_t i = 0; i < nx; i += 64) {
        const int n = static_cast<int>(std::min<std::int64_t>(64, nx - i));
        row[i >> 6] = load_bits(data, position + static_cast<std::uint64_t>(i), n);
      }
      position += static_cast<std::uint64_t>(nx);
    }
  }
}

}  // namespace

namespace encode {

void pack_raw_bits(const BitVolume& volume, BitPacker& packer, ByteSink& sink) {
  const std::int64_t nx = volume.grid().dims.x;
  for (std::int64_t k = 0; k < volume.grid().dims.z; ++k) {
    for (std::int64_t j = 0; j < volume.grid().dims.y; ++j) {
      const std::uint64_t* row = volume.row(j, k);
      for (std::int64_t i = 0; i < nx; i += 64) {
        const int n = static_cast<int>(std::min<std::int64_t>(64, nx - i));
        const std::uint64_t mask = n == 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << n) - 1;
        packer.put(row[i >> 6] & mask, n);
      }
      if (packer.buffered() >= kFlushBytes) packer.flush(sink, false);
    }
  }
}

void write_raw_bytes(const BitVolume& volume, ByteSink& sink) { write_bytes(volume, sink); }

}  // namespace encode

void write_raw(const BitVolume& volume, RawPacking packing, ByteSink& sink) {
  encode::require_voxels(volume.grid(), "raw writer");
  if (packing == RawPacking::bytes)
    write_bytes(volume, sink);
  else
    write_bits(volume, sink);
}

BitVolume read_raw(std::span<const std::uint8_t> data, const Grid& grid, RawPacking packing,
                   const ReadLimits& limits) {
  check_grid(grid);
  const std::uint64_t voxels = grid.voxel_count();
  if (packing == RawPacking::bytes)
    check_size(data.size(), voxels, "bytes");
  else
    check_size(data.size(), (voxels + 7) / 8, "bits");
  encode::check_read_limit(encode::bit_volume_bytes(grid.dims), limits, "raw reader");
  BitVolume volume(grid);
  if (packing == RawPacking::bytes)
    read_bytes(data, volume);
  else
    read_bits(data, volume);
  return volume;
}

}  // namespace voxd
