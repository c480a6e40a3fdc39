// Reads voxd's RLE stream (proto-schemas/rle-format.md). The input is
// untrusted: a first pass checks every block and run without allocating the
// volume, so a header that lies about the dims costs nothing; only a stream
// that is valid end to end gets its volume allocated and filled (second pass).
#include <algorithm>
#include <bit>
#include <cstdint>
#include <exception>
#include <string>
#include <vector>

#include "encode/bit_runs.h"
#include "encode/byte_cursor.h"
#include "encode/rle_stream.h"
#include "encode/source_window.h"
#include "encode/volume_checks.h"
#include "voxd/encode/rle_slabs.h"
#include "voxd/encode/volume_format.h"
#include "voxd/parallel.h"

namespace voxd {
namespace {

using encode::ByteCursor;

std::string hex_byte(std::uint8_t b) {
  const char* digits = "0123456789abcdef";
  return std::string("0x") + digits[b >> 4] + digits[b & 15];
}

// One slab block's payload and where it starts in the stream.
struct SlabBlock {
  std::span<const std::uint8_t> payload;
  std::size_t at;
};

// Checks the head of slab block k of nz (tag, index) and reads its payload
// length.
std::uint64_t read_slab_head(ByteCursor& in, std::int64_t k, std::int64_t nz) {
  const std::size_t block_at = in.offset();
  const std::uint8_t tag = in.u8("a slab block tag");
  if (tag == encode::kEndTag)
    in.fail(ErrorCode::malformed_input, "end block at byte " + std::to_string(block_at) + " after " +
                                            std::to_string(k) + " slab blocks; the header's dims give " +
                                            std::to_string(nz) + " slabs");
  if (tag != encode::kSlabTag)
    in.fail(ErrorCode::malformed_input, "byte " + std::to_string(block_at) +
                                            ": expected a slab block (tag 0x53 'S'), found " + hex_byte(tag));
  const std::uint64_t index = in.varint("a slab index");
  if (index != static_cast<std::uint64_t>(k))
    in.fail(ErrorCode::malformed_input, "slab block at byte " + std::to_string(block_at) + " has index " +
                                            std::to_string(index) + " where slab " + std::to_string(k) +
                                            " was expected (slabs come in order from 0)");
  return in.varint("a slab payload length");
}

// Checks the framing of slab block k of nz and steps over it.
SlabBlock read_slab_block(ByteCursor& in, std::int64_t k, std::int64_t nz) {
  const std::uint64_t length = read_slab_head(in, k, nz);
  const std::size_t payload_at = in.offset();
  return {in.bytes(length, "a slab payload"), payload_at};
}

// Checks the end block after nz slab blocks.
void read_end_head(ByteCursor& in, std::int64_t nz) {
  const std::size_t end_at = in.offset();
  const std::uint8_t tag = in.u8("the end block");
  if (tag == encode::kSlabTag)
    in.fail(ErrorCode::malformed_input, "slab block at byte " + std::to_string(end_at) +
                                            " is one more than the " + std::to_string(nz) +
                                            " slabs the header's dims give");
  if (tag != encode::kEndTag)
    in.fail(ErrorCode::malformed_input, "byte " + std::to_string(end_at) +
                                            ": expected the end block (tag 0x45 'E'), found " + hex_byte(tag));
  const std::uint64_t count = in.varint("the end block's slab count");
  if (count != static_cast<std::uint64_t>(nz))
    in.fail(ErrorCode::malformed_input, "the end block counts " + std::to_string(count) + " slabs, the header " +
                                            std::to_string(nz));
}

// Checks the end block after nz slab blocks and that nothing follows it.
void read_end_block(ByteCursor& in, std::int64_t nz) {
  read_end_head(in, nz);
  if (!in.at_end())
    in.fail(ErrorCode::malformed_input, std::to_string(in.remaining()) + " unexpected bytes after the end block");
}

// Checks the framing of the slab blocks and the end block, calling
// visit(k, payload, payload_offset) for each slab in order. Takes the cursor
// by value so that each pass starts from the first block.
template <class Visit>
void walk_slab_blocks(ByteCursor in, std::int64_t nz, const Visit& visit) {
  for (std::int64_t k = 0; k < nz; ++k) {
    const SlabBlock block = read_slab_block(in, k, nz);
    visit(k, block.payload, block.at);
  }
  read_end_block(in, nz);
}

ByteCursor payload_cursor(std::span<const std::uint8_t> payload, std::size_t payload_at, std::int64_t k) {
  // The block's length says the payload is complete, so a run cut short by
  // its end is a malformed block, not a truncated stream.
  return ByteCursor(payload, ErrorCode::malformed_input, "RLE stream: slab " + std::to_string(k) + " payload",
                    payload_at);
}

void check_covered(const ByteCursor& in, std::uint64_t covered, std::uint64_t slab_voxels) {
  if (covered != slab_voxels)
    in.fail(ErrorCode::malformed_input, "the runs cover " + std::to_string(covered) + " of the slab's " +
                                            std::to_string(slab_voxels) + " voxels");
}

// Bit payload: varint run lengths alternating 0s and 1s, 0s first; calls
// on_ones(first_voxel, length) for each non-empty run of 1s.
template <class OnOnes>
void decode_bit_payload(ByteCursor in, std::uint64_t slab_voxels, const OnOnes& on_ones) {
  std::uint64_t position = 0;
  bool ones = false;
  while (!in.at_end()) {
    const std::uint64_t run = in.varint("a run length");
    if (run > slab_voxels - position)
      in.fail(ErrorCode::malformed_input,
              "the runs add up to more than the slab's " + std::to_string(slab_voxels) + " voxels");
    if (ones && run > 0) on_ones(position, run);
    position += run;
    ones = !ones;
  }
  check_covered(in, position, slab_voxels);
}

// The value of a run: one byte, two or four little-endian bytes, or the
// four bytes r, g, b, a of a colour.
inline std::uint8_t read_value(ByteCursor& in, std::uint8_t*) { return in.u8("a run value"); }
inline std::uint16_t read_value(ByteCursor& in, std::uint16_t*) {
  const std::uint16_t lo = in.u8("a run value");
  return static_cast<std::uint16_t>(lo | (in.u8("a run value") << 8));
}
inline float read_value(ByteCursor& in, float*) {
  std::uint32_t bits = 0;
  for (int b = 0; b < 4; ++b) bits |= static_cast<std::uint32_t>(in.u8("a run value")) << (8 * b);
  return std::bit_cast<float>(bits);
}

inline Rgba8 read_value(ByteCursor& in, Rgba8*) {
  Rgba8 c;
  c.r = in.u8("a run value");
  c.g = in.u8("a run value");
  c.b = in.u8("a run value");
  c.a = in.u8("a run value");
  return c;
}

// u8 / u16 / f32 / rgba8 payload: (varint run length, value) pairs; calls
// on_run(first_voxel, length, value) for each.
template <class T, class OnRun>
void decode_value_payload(ByteCursor in, std::uint64_t slab_voxels, const OnRun& on_run) {
  std::uint64_t position = 0;
  while (!in.at_end()) {
    const std::uint64_t run = in.varint("a run length");
    const T value = read_value(in, static_cast<T*>(nullptr));
    if (run > slab_voxels - position)
      in.fail(ErrorCode::malformed_input,
              "the runs add up to more than the slab's " + std::to_string(slab_voxels) + " voxels");
    on_run(position, run, value);
    position += run;
  }
  check_covered(in, position, slab_voxels);
}

// Sets `length` voxels from slab-linear index `first` (i + nx * j); a run may
// continue over several rows.
void set_run(std::uint64_t* slab, std::int64_t row_words, std::int64_t nx, std::uint64_t first,
             std::uint64_t length) {
  auto j = static_cast<std::int64_t>(first / static_cast<std::uint64_t>(nx));
  auto i = static_cast<std::int64_t>(first % static_cast<std::uint64_t>(nx));
  while (length > 0) {
    const auto n = static_cast<std::int64_t>(std::min<std::uint64_t>(length, static_cast<std::uint64_t>(nx - i)));
    encode::set_bit_range(slab + j * row_words, i, i + n);
    length -= static_cast<std::uint64_t>(n);
    i = 0;
    ++j;
  }
}

encode::RleHeader read_header_of_type(ByteCursor& in, encode::RleValueType wanted, const char* reader) {
  const encode::RleHeader header = encode::read_rle_header(in);
  if (header.value_type != wanted)
    in.fail(ErrorCode::malformed_input, std::string("the stream holds ") + to_string(header.value_type) +
                                            " values; " + reader + " reads only " + to_string(wanted) +
                                            " streams");
  return header;
}

std::uint64_t slab_voxel_count(const Grid& grid) {
  return static_cast<std::uint64_t>(grid.dims.x) * static_cast<std::uint64_t>(grid.dims.y);
}

template <class T>
DenseVolume<T> read_rle_values(std::span<const std::uint8_t> data, const ReadLimits& limits,
                               encode::RleValueType type, const char* reader) {
  ByteCursor in(data, ErrorCode::truncated_input, "RLE stream");
  const encode::RleHeader header = read_header_of_type(in, type, reader);
  const Grid& grid = header.grid;
  const std::uint64_t slab_voxels = slab_voxel_count(grid);

  walk_slab_blocks(in, grid.dims.z, [&](std::int64_t k, std::span<const std::uint8_t> payload, std::size_t at) {
    decode_value_payload<T>(payload_cursor(payload, at, k), slab_voxels, [](std::uint64_t, std::uint64_t, T) {});
  });
  encode::check_read_limit(grid.voxel_count() * sizeof(T), limits, "RLE reader");

  DenseVolume<T> volume(grid, T{});
  walk_slab_blocks(in, grid.dims.z, [&](std::int64_t k, std::span<const std::uint8_t> payload, std::size_t at) {
    T* slab = volume.slab(k);
    decode_value_payload<T>(payload_cursor(payload, at, k), slab_voxels,
                            [&](std::uint64_t first, std::uint64_t length, T value) { std::fill_n(slab + first, length, value); });
  });
  return volume;
}

}  // namespace

BitVolume read_rle_bits(std::span<const std::uint8_t> data, const ReadLimits& limits) {
  ByteCursor in(data, ErrorCode::truncated_input, "RLE stream");
  const encode::RleHeader header = read_header_of_type(in, encode::RleValueType::bit, "read_rle_bits");
  const Grid& grid = header.grid;
  const std::uint64_t slab_voxels = slab_voxel_count(grid);

  walk_slab_blocks(in, grid.dims.z, [&](std::int64_t k, std::span<const std::uint8_t> payload, std::size_t at) {
    decode_bit_payload(payload_cursor(payload, at, k), slab_voxels, [](std::uint64_t, std::uint64_t) {});
  });
  encode::check_read_limit(encode::bit_volume_bytes(grid.dims), limits, "RLE reader");

  BitVolume volume(grid);
  walk_slab_blocks(in, grid.dims.z, [&](std::int64_t k, std::span<const std::uint8_t> payload, std::size_t at) {
    std::uint64_t* slab = volume.slab(k);
    decode_bit_payload(payload_cursor(payload, at, k), slab_voxels, [&](std::uint64_t first, std::uint64_t length) {
      set_run(slab, volume.row_words(), grid.dims.x, first, length);
    });
  });
  return volume;
}

DenseVolume<std::uint8_t> read_rle_u8(std::span<const std::uint8_t> data, const ReadLimits& limits) {
  return read_rle_values<std::uint8_t>(data, limits, encode::RleValueType::u8, "read_rle_u8");
}

DenseVolume<float> read_rle_f32(std::span<const std::uint8_t> data, const ReadLimits& limits) {
  return read_rle_values<float>(data, limits, encode::RleValueType::f32, "read_rle_f32");
}

DenseVolume<std::uint16_t> read_rle_u16(std::span<const std::uint8_t> data, const ReadLimits& limits) {
  return read_rle_values<std::uint16_t>(data, limits, encode::RleValueType::u16, "read_rle_u16");
}

DenseVolume<Rgba8> read_rle_rgba8(std::span<const std::uint8_t> data, const ReadLimits& limits) {
  return read_rle_values<Rgba8>(data, limits, encode::RleValueType::rgba8, "read_rle_rgba8");
}

namespace {

using encode::SourceWindow;

// The longest block head: a tag and two varints of at most 10 bytes.
constexpr std::size_t kMaxBlockHead = 21;
// The header is small but for its metadata JSON: read in growing pieces.
constexpr std::size_t kMaxHeaderBytes = std::size_t{64} << 20;

// The stream's header, from as many bytes as it takes.
encode::RleHeader read_header(SourceWindow& window) {
  for (std::size_t n = 4096;; n *= 4) {
    const auto bytes = window.peek(n);
    ByteCursor in(bytes, ErrorCode::truncated_input, "RLE stream");
    try {
      encode::RleHeader header = encode::read_rle_header(in);
      window.consume(in.offset());
      return header;
    } catch (const Error& e) {
      // More bytes may complete it, unless the source has no more.
      if (e.code() != ErrorCode::truncated_input || bytes.size() < n || n >= kMaxHeaderBytes) throw;
    }
  }
}

encode::RleHeader read_header_of_type(SourceWindow& window, encode::RleValueType wanted, const char* reader) {
  const encode::RleHeader header = read_header(window);
  if (header.value_type != wanted)
    throw Error(ErrorCode::malformed_input, std::string("RLE stream: the stream holds ") + to_string(header.value_type) +
                                                " values; " + reader + " reads only " + to_string(wanted) + " streams");
  return header;
}

// The next slab block's payload, k of nz, whose runs cannot need more than
// `max_payload` bytes (a bound that keeps a corrupt length from taking the
// rest of the stream into memory). The span is valid until the next peek.
// A slab block's head, read but not yet consumed: its payload's length and
// the head's own.
struct SlabHead {
  std::uint64_t length;
  std::size_t bytes;
};

SlabHead peek_slab_head(SourceWindow& window, std::int64_t k, std::int64_t nz, std::uint64_t max_payload) {
  ByteCursor head(window.peek(kMaxBlockHead), ErrorCode::truncated_input, "RLE stream", window.offset());
  const std::uint64_t length = read_slab_head(head, k, nz);
  if (length > max_payload)
    head.fail(ErrorCode::malformed_input, "slab " + std::to_string(k) + " declares a payload of " + std::to_string(length) +
                                              " bytes, more than the runs of one layer can take");
  return {length, head.offset() - window.offset()};
}

// Steps over the head peek_slab_head read and takes its payload.
SlabBlock take_slab_block(SourceWindow& window, const SlabHead& head) {
  window.consume(head.bytes);
  const std::size_t at = window.offset();
  const auto payload = window.peek(static_cast<std::size_t>(head.length));
  if (payload.size() < head.length)
    throw Error(ErrorCode::truncated_input,
                "RLE stream: data ends inside a slab payload at byte " + std::to_string(at));
  window.consume(payload.size());
  return {payload, at};
}

SlabBlock next_slab_block(SourceWindow& window, std::int64_t k, std::int64_t nz, std::uint64_t max_payload) {
  return take_slab_block(window, peek_slab_head(window, k, nz, max_payload));
}

void read_end(SourceWindow& window, std::int64_t nz) {
  ByteCursor head(window.peek(kMaxBlockHead), ErrorCode::truncated_input, "RLE stream", window.offset());
  read_end_head(head, nz);
  window.consume(head.offset() - window.offset());
  // In memory, all that follows is counted; from a source, a few bytes.
  const std::size_t look = window.in_memory() ? SIZE_MAX : kMaxBlockHead;
  if (const std::size_t more = window.peek(look).size(); more > 0)
    throw Error(ErrorCode::malformed_input, "RLE stream: " + std::string(more == look ? "at least " : "") +
                                                std::to_string(more) + " unexpected bytes after the end block");
}

// The most bytes one layer's runs take: every run a 10-byte varint (and a
// value of up to 4 bytes), twice as many runs as voxels for bits.
std::uint64_t max_bit_payload(std::uint64_t slab_voxels) { return 10 * (2 * slab_voxels + 2); }
std::uint64_t max_value_payload(std::uint64_t slab_voxels) { return 14 * (slab_voxels + 1); }

}  // namespace

Grid read_rle_bit_grid(std::span<const std::uint8_t> data) {
  ByteCursor in(data, ErrorCode::truncated_input, "RLE stream");
  return read_header_of_type(in, encode::RleValueType::bit, "read_rle_bit_grid").grid;
}

Grid read_rle_bit_grid(ByteSource& source) {
  SourceWindow window(source);
  return read_header_of_type(window, encode::RleValueType::bit, "read_rle_bit_grid").grid;
}

void read_rle_bit_slabs(ByteSource& source, std::int64_t slab_layers, const BitSlabConsumer& consume,
                        const ReadLimits& limits) {
  SourceWindow window(source);
  const Grid grid = read_header_of_type(window, encode::RleValueType::bit, "read_rle_bit_slabs").grid;
  const std::int64_t nz = grid.dims.z;
  const std::uint64_t slab_voxels = slab_voxel_count(grid);
  const std::int64_t layers = std::clamp<std::int64_t>(slab_layers, 1, std::max<std::int64_t>(nz, 1));
  encode::check_read_limit(encode::bit_volume_bytes({grid.dims.x, grid.dims.y, layers}), limits, "RLE slab reader");
  for (std::int64_t k0 = 0; k0 < nz; k0 += layers) {
    const std::int64_t n = std::min(layers, nz - k0);
    // A fresh slab comes zeroed from the OS, as the streamed voxelizer's do.
    BitVolume slab(slab_grid(grid, k0, n));
    for (std::int64_t k = k0; k < k0 + n; ++k) {
      const SlabBlock block = next_slab_block(window, k, nz, max_bit_payload(slab_voxels));
      std::uint64_t* layer = slab.slab(k - k0);
      decode_bit_payload(payload_cursor(block.payload, block.at, k), slab_voxels, [&](std::uint64_t first, std::uint64_t length) {
        set_run(layer, slab.row_words(), grid.dims.x, first, length);
      });
    }
    consume(k0, slab);
  }
  read_end(window, nz);
}

void read_rle_bit_slabs(std::span<const std::uint8_t> data, std::int64_t slab_layers, const BitSlabConsumer& consume,
                        const ReadLimits& limits) {
  SpanSource source(data);
  read_rle_bit_slabs(source, slab_layers, consume, limits);
}

namespace {

// Appends layer k's rows, from its slab block, to `into` (whose rows before
// are whole): the stream's runs cut at the rows' ends. Rows are closed in
// order; a run is held until the next one shows it is maximal (a stream
// may split a run with a 0-run of length 0).
void append_layer_runs(const SlabBlock& block, std::int64_t k, const Grid& grid, RunSlab& into) {
  const std::int64_t nx = grid.dims.x, ny = grid.dims.y;
  std::int64_t row = 0;
  std::uint32_t held_begin = 0, held_end = 0;
  std::int64_t held_row = -1;
  auto flush = [&] {
    if (held_row < 0) return;
    for (; row < held_row; ++row) into.end_row();
    into.add_run(held_begin, held_end);
    held_row = -1;
  };
  decode_bit_payload(payload_cursor(block.payload, block.at, k), slab_voxel_count(grid),
                     [&](std::uint64_t first, std::uint64_t length) {
                       auto j = static_cast<std::int64_t>(first / static_cast<std::uint64_t>(nx));
                       auto i = static_cast<std::int64_t>(first % static_cast<std::uint64_t>(nx));
                       while (length > 0) {
                         const auto n = static_cast<std::int64_t>(
                             std::min<std::uint64_t>(length, static_cast<std::uint64_t>(nx - i)));
                         if (held_row == j && held_end == static_cast<std::uint32_t>(i)) {
                           held_end = static_cast<std::uint32_t>(i + n);
                         } else {
                           flush();
                           held_row = j;
                           held_begin = static_cast<std::uint32_t>(i);
                           held_end = static_cast<std::uint32_t>(i + n);
                         }
                         length -= static_cast<std::uint64_t>(n);
                         i = 0;
                         ++j;
                       }
                     });
  flush();
  for (; row < ny; ++row) into.end_row();
}

}  // namespace

std::uint64_t run_reader_batch_bytes(int threads) {
  if ((threads > 0 ? threads : default_thread_count()) <= 1) return 0;
  // Payload P and rows R at most: P copied, at most P / 2 + R runs of 8
  // bytes (a row may cut a run; every layer has a row), R + layers <= 2 R
  // row starts of 4 bytes.
  return 5 * std::uint64_t{kRunReaderBatchPayload} + 24 * std::uint64_t{kRunReaderBatchRows};
}

void read_rle_run_slabs(ByteSource& source, std::int64_t slab_layers, const RunSlabConsumer& consume,
                        const ReadLimits& limits, int threads) {
  SourceWindow window(source);
  const Grid grid = read_header_of_type(window, encode::RleValueType::bit, "read_rle_run_slabs").grid;
  const std::int64_t ny = grid.dims.y, nz = grid.dims.z;
  const std::uint64_t slab_voxels = slab_voxel_count(grid);
  // One layer's runs: at most one a pair of voxels and one more a row (a
  // stored run may go on from one row into the next), two bounds of 4
  // bytes each, and a row's start. A slab's bounds are indexed in 32 bits.
  const std::uint64_t layer_runs = slab_voxels / 2 + static_cast<std::uint64_t>(ny) + 1;
  encode::check_read_limit(8 * layer_runs + 4 * static_cast<std::uint64_t>(ny + 1), limits, "RLE run reader");
  if (kRunSlabRuns + layer_runs > UINT32_MAX / 2)
    throw Error(ErrorCode::limit_exceeded, "RLE run reader: a layer of " + std::to_string(slab_voxels) +
                                               " voxels may hold more runs than a run slab indexes");
  // A slab's rows are indexed too (a start each), so it holds at most
  // kRunSlabRuns rows as well as runs: a slab of every layer of a large
  // grid would otherwise reserve a start for each of its rows at once.
  const std::int64_t row_bound = std::max<std::int64_t>(1, static_cast<std::int64_t>(kRunSlabRuns) / std::max<std::int64_t>(ny, 1));
  const std::int64_t layers = std::clamp<std::int64_t>(std::min(slab_layers, row_bound), 1, std::max<std::int64_t>(nz, 1));
  const int nthreads = threads > 0 ? threads : default_thread_count();
  const std::uint64_t max_payload = max_bit_payload(slab_voxels);

  RunSlab slab;
  std::int64_t k0 = 0;
  // Layer k's rows are in the slab: hands the slab on when it is full.
  auto layer_added = [&](std::int64_t k) {
    const std::int64_t in_slab = k + 1 - k0;
    if (in_slab == slab.grid().dims.z || slab.run_count() >= kRunSlabRuns) {
      if (in_slab < slab.grid().dims.z) slab.set_layers(in_slab);
      consume(k0, slab);
      k0 = k + 1;
    }
  };
  auto start_slab = [&](std::int64_t k) {
    if (k != k0) return;
    slab.reset(slab_grid(grid, k0, std::min(layers, nz - k0)));
    // Room for the most runs a slab can hold (it is handed on once it holds
    // kRunSlabRuns, so one layer more at most), so that it never grows by
    // copying what it holds: 64 MiB at a time, on pages just faulted in.
    // Only the pages written become memory.
    slab.reserve_runs(static_cast<std::size_t>(
        std::min(kRunSlabRuns + layer_runs, static_cast<std::uint64_t>(slab.grid().dims.z) * layer_runs)));
  };

  // A batch: the blocks of layers [k, k + blocks.size()), each decoded into
  // a slab of its own on any thread, then appended in order. A source that
  // is not in memory reuses its buffer when it reads on, so a block is
  // copied before the next head is read.
  std::vector<SlabBlock> blocks;
  std::vector<std::vector<std::uint8_t>> copies;
  // Apart in memory: threads decoding neighbouring layers would otherwise
  // write the same cache lines (the vectors' ends) on every run.
  struct alignas(128) Decoded {
    RunSlab runs;
  };
  std::vector<Decoded> decoded;
  std::vector<std::exception_ptr> errors;
  std::vector<const RunSlab*> segment;
  for (std::int64_t k = 0; k < nz;) {
    blocks.clear();
    std::exception_ptr framing;  // a bad block head after the batch's good ones
    std::uint64_t payload = 0;
    try {
      while (k + static_cast<std::int64_t>(blocks.size()) < nz) {
        const auto b = static_cast<std::int64_t>(blocks.size());
        if (b > 0) {
          if (nthreads <= 1 || payload >= kRunReaderBatchPayload ||
              static_cast<std::uint64_t>((b + 1) * ny) > kRunReaderBatchRows)
            break;
          if (!window.in_memory()) {
            if (copies.size() < blocks.size()) copies.resize(blocks.size());
            copies[b - 1].assign(blocks[b - 1].payload.begin(), blocks[b - 1].payload.end());
            blocks[b - 1].payload = copies[b - 1];
          }
        }
        const SlabHead head = peek_slab_head(window, k + b, nz, max_payload);
        if (b > 0 && payload + head.length > kRunReaderBatchPayload) break;
        blocks.push_back(take_slab_block(window, head));
        payload += head.length;
      }
    } catch (...) {
      if (blocks.empty()) throw;
      framing = std::current_exception();
    }
    if (blocks.size() == 1) {
      start_slab(k);
      append_layer_runs(blocks[0], k, grid, slab);
      layer_added(k++);
    } else {
      const auto n = static_cast<std::int64_t>(blocks.size());
      if (decoded.size() < blocks.size()) decoded.resize(blocks.size());
      errors.assign(blocks.size(), nullptr);
      parallel_for(0, n, 1, nthreads, [&](std::int64_t b0, std::int64_t b1) {
        for (std::int64_t b = b0; b < b1; ++b) {
          const auto u = static_cast<std::size_t>(b);
          try {
            decoded[u].runs.reset(slab_grid(grid, k + b, 1));
            append_layer_runs(blocks[u], k + b, grid, decoded[u].runs);
          } catch (...) {
            errors[u] = std::current_exception();
          }
        }
      });
      // The layers go into the slab in segments: as many as it takes before
      // it is handed on, or before a layer that failed, whose error then
      // comes after the layers before it, as on one thread. A segment is
      // appended at once, copied on every thread; only its last layer can
      // fill the slab, so it alone is checked.
      for (std::size_t b = 0; b < blocks.size();) {
        if (errors[b]) std::rethrow_exception(errors[b]);
        start_slab(k);
        segment.clear();
        std::size_t runs = slab.run_count();
        while (b + segment.size() < blocks.size() && !errors[b + segment.size()]) {
          const RunSlab& layer = decoded[b + segment.size()].runs;
          segment.push_back(&layer);
          runs += layer.run_count();
          if (k + static_cast<std::int64_t>(segment.size()) - k0 == slab.grid().dims.z || runs >= kRunSlabRuns) break;
        }
        slab.append_rows(segment, nthreads);
        k += static_cast<std::int64_t>(segment.size()) - 1;
        layer_added(k++);
        b += segment.size();
      }
    }
    if (framing) std::rethrow_exception(framing);
  }
  // The slab's runs (a full slab's are 64 MiB and more) are the last thing
  // freed, and would be by this thread alone.
  slab.free_on_every_thread(nthreads);
  read_end(window, nz);
}

void read_rle_run_slabs(std::span<const std::uint8_t> data, std::int64_t slab_layers, const RunSlabConsumer& consume,
                        const ReadLimits& limits, int threads) {
  SpanSource source(data);
  read_rle_run_slabs(source, slab_layers, consume, limits, threads);
}

namespace {

template <class T>
void read_value_slabs(SourceWindow& window, const Grid& grid, std::int64_t slab_layers, const ValueSlabConsumer& consume,
                      const ReadLimits& limits) {
  const std::int64_t nz = grid.dims.z;
  const std::uint64_t slab_voxels = slab_voxel_count(grid);
  const std::int64_t layers = std::clamp<std::int64_t>(slab_layers, 1, std::max<std::int64_t>(nz, 1));
  encode::check_read_limit(slab_voxels * static_cast<std::uint64_t>(layers) * sizeof(T), limits, "RLE slab reader");
  for (std::int64_t k0 = 0; k0 < nz; k0 += layers) {
    const std::int64_t n = std::min(layers, nz - k0);
    ValueVolume slab{std::in_place_type<DenseVolume<T>>, slab_grid(grid, k0, n), T{}};
    DenseVolume<T>& values = std::get<DenseVolume<T>>(slab);
    for (std::int64_t k = k0; k < k0 + n; ++k) {
      const SlabBlock block = next_slab_block(window, k, nz, max_value_payload(slab_voxels));
      T* layer = values.slab(k - k0);
      decode_value_payload<T>(payload_cursor(block.payload, block.at, k), slab_voxels,
                              [&](std::uint64_t first, std::uint64_t length, T value) { std::fill_n(layer + first, length, value); });
    }
    consume(k0, slab);
  }
  read_end(window, nz);
}

}  // namespace

void read_rle_value_slabs(ByteSource& source, std::int64_t slab_layers, const ValueSlabConsumer& consume,
                          const ReadLimits& limits) {
  SourceWindow window(source);
  const encode::RleHeader header = read_header(window);
  switch (header.value_type) {
    case encode::RleValueType::u8: return read_value_slabs<std::uint8_t>(window, header.grid, slab_layers, consume, limits);
    case encode::RleValueType::f32: return read_value_slabs<float>(window, header.grid, slab_layers, consume, limits);
    case encode::RleValueType::rgba8: return read_value_slabs<Rgba8>(window, header.grid, slab_layers, consume, limits);
    default: break;
  }
  throw Error(ErrorCode::malformed_input, std::string("RLE stream: the stream holds ") + to_string(header.value_type) +
                                              " values; read_rle_value_slabs reads u8, f32 and rgba8 streams");
}

void read_rle_value_slabs(std::span<const std::uint8_t> data, std::int64_t slab_layers, const ValueSlabConsumer& consume,
                          const ReadLimits& limits) {
  SpanSource source(data);
  read_rle_value_slabs(source, slab_layers, consume, limits);
}

std::string read_rle_metadata(std::span<const std::uint8_t> data) {
  ByteCursor in(data, ErrorCode::truncated_input, "RLE stream");
  return encode::read_rle_header(in).metadata_json;
}

}  // namespace voxd
