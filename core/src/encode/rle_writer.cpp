// Writes voxd's RLE stream (proto-schemas/rle-format.md). Slabs are encoded in
// parallel a few ahead of the writer and written in order, so the memory in
// flight is a handful of encoded slabs, never a copy of the volume.
#include <algorithm>
#include <cmath>
#include <bit>
#include <cstring>
#include <functional>
#include <span>
#include <type_traits>
#include <variant>
#include <vector>

#include <nlohmann/json.hpp>

#include "encode/bit_runs.h"
#include "encode/byte_buffer.h"
#include "encode/ordered_pipeline.h"
#include "encode/rle_stream.h"
#include "encode/volume_checks.h"
#include "voxd/parallel.h"
#include "voxd/encode/volume_format.h"

namespace voxd {
namespace {

using encode::ByteBuffer;

// Room left at the front of each slab buffer for the block header (tag, slab
// index, payload length), filled in once the payload length is known so that
// each block goes to the sink in one write.
constexpr std::size_t kBlockHeaderRoom = 1 + 2 * encode::kMaxVarintBytes;
// Input bytes of the slabs encoded ahead of the writer: enough to keep the
// threads busy, while worst-case (alternating) slabs still stay a few MiB.
constexpr std::size_t kInFlightInputBytes = std::size_t{2} << 20;
// Below this, starting threads costs more than the encoding.
constexpr std::size_t kParallelMinBytes = std::size_t{256} << 10;

// Layer k's block: its payload is in `buffer` after kBlockHeaderRoom bytes
// left for the header, which goes just before it, so the block is one span
// (to the sink in one write).
std::span<const std::uint8_t> finish_block(std::int64_t k, ByteBuffer& buffer) {
  const std::uint64_t payload = buffer.size() - kBlockHeaderRoom;
  std::uint8_t header[kBlockHeaderRoom];
  std::uint8_t* end = header;
  *end++ = encode::kSlabTag;
  end = encode::put_varint(end, static_cast<std::uint64_t>(k));
  end = encode::put_varint(end, payload);
  const auto header_size = static_cast<std::size_t>(end - header);
  std::uint8_t* block = buffer.data() + kBlockHeaderRoom - header_size;
  std::memcpy(block, header, header_size);
  return {block, header_size + payload};
}

void write_block(std::int64_t k, ByteBuffer& buffer, ByteSink& sink) {
  const std::span<const std::uint8_t> block = finish_block(k, buffer);
  sink.write(block.data(), block.size());
}

// Encodes slabs [k_begin, k_end) with encode_slab(k, buffer), in parallel,
// and writes their blocks in order.
void write_slab_block_range(std::int64_t k_begin, std::int64_t k_end, std::size_t slab_input_bytes,
                            const std::function<void(std::int64_t, ByteBuffer&)>& encode_slab, ByteSink& sink) {
  const std::int64_t nz = k_end - k_begin;
  const bool small = slab_input_bytes * static_cast<std::size_t>(nz) < kParallelMinBytes;
  const int threads = small ? 1 : default_thread_count();
  // Slabs in flight: about kInFlightInputBytes of input, but at least two per
  // thread so that none idles, and no more than there are slabs.
  const auto per_thread = static_cast<std::size_t>(2 * threads);
  std::size_t slots = kInFlightInputBytes / std::max<std::size_t>(slab_input_bytes, 1);
  slots = std::clamp(slots, per_thread, std::max<std::size_t>(64, per_thread));
  std::vector<ByteBuffer> buffers(std::min(slots, static_cast<std::size_t>(nz)));
  encode::run_ordered_pipeline(
      nz, threads, buffers.size(),
      [&](std::int64_t i, std::size_t slot) {
        ByteBuffer& buffer = buffers[slot];
        buffer.reset(kBlockHeaderRoom);
        encode_slab(k_begin + i, buffer);
      },
      [&](std::int64_t i, std::size_t slot) { write_block(k_begin + i, buffers[slot], sink); });
}

void write_end_block(std::int64_t nz, ByteSink& sink) {
  std::uint8_t end_block[1 + encode::kMaxVarintBytes];
  end_block[0] = encode::kEndTag;
  const std::uint8_t* end = encode::put_varint(end_block + 1, static_cast<std::uint64_t>(nz));
  sink.write(end_block, static_cast<std::size_t>(end - end_block));
}

// Slabs [0, nz), then the end block.
void write_slab_blocks(std::int64_t nz, std::size_t slab_input_bytes,
                       const std::function<void(std::int64_t, ByteBuffer&)>& encode_slab, ByteSink& sink) {
  write_slab_block_range(0, nz, slab_input_bytes, encode_slab, sink);
  write_end_block(nz, sink);
}

void write_header(const Grid& grid, encode::RleValueType type, ByteSink& sink, const std::string& metadata = {}) {
  const std::vector<std::uint8_t> header = encode::encode_rle_header(grid, type, metadata);
  sink.write(header.data(), header.size());
}

// Bit slab payload: alternating run lengths, 0s first; runs cross rows.
void encode_bit_slab(const BitVolume& volume, std::int64_t k, ByteBuffer& out) {
  const std::int64_t nx = volume.grid().dims.x;
  encode::BitRunSplitter runs;
  const auto put = [&out](bool, std::uint64_t length) { out.put_varint(length); };
  for (std::int64_t j = 0; j < volume.grid().dims.y; ++j) runs.add_row(volume.row(j, k), nx, put);
  runs.finish(put);
}

// The same payload from a slab's runs (layer k of it): the row's runs are
// already maximal, and a run reaching a row's end joins one starting the
// next row, as the bits' runs do.
void encode_run_layer(const RunSlab& slab, std::int64_t k, ByteBuffer& out) {
  const auto nx = static_cast<std::uint64_t>(slab.grid().dims.x);
  const std::uint64_t total = nx * static_cast<std::uint64_t>(slab.grid().dims.y);
  std::uint64_t emitted = 0;  // voxels [0, emitted) are in the payload
  std::uint64_t begin = 0, end = 0;  // the ones run not yet written, when open
  bool open = false;
  const auto flush = [&] {
    out.put_varint(begin - emitted);  // the 0s before it (0 only at the layer's start)
    out.put_varint(end - begin);
    emitted = end;
  };
  for (std::int64_t j = 0; j < slab.grid().dims.y; ++j) {
    const std::uint64_t base = static_cast<std::uint64_t>(j) * nx;
    const auto runs = slab.row(j, k);
    for (std::size_t r = 0; r < runs.size(); r += 2) {
      const std::uint64_t b = base + runs[r], e = base + runs[r + 1];
      if (open && b == end) {
        end = e;
        continue;
      }
      if (open) flush();
      open = true;
      begin = b;
      end = e;
    }
  }
  if (open) flush();
  if (emitted < total || total == 0) out.put_varint(total - emitted);
}

// Length of the run of bytes equal to values[begin] starting at begin,
// comparing 8 bytes at a time.
std::size_t byte_run_length(const std::uint8_t* values, std::size_t begin, std::size_t n) {
  const std::uint8_t v = values[begin];
  const std::uint64_t pattern = 0x0101010101010101ull * v;
  std::size_t i = begin + 1;
  while (i + 8 <= n) {
    std::uint64_t word;
    std::memcpy(&word, values + i, 8);
    if (const std::uint64_t diff = word ^ pattern; diff != 0) {
      // The first differing byte in memory order is the lowest one on a
      // little-endian machine, the highest on a big-endian one.
      const int byte = std::endian::native == std::endian::little ? std::countr_zero(diff) / 8
                                                                  : std::countl_zero(diff) / 8;
      return i + static_cast<std::size_t>(byte) - begin;
    }
    i += 8;
  }
  while (i < n && values[i] == v) ++i;
  return i - begin;
}

// u8 slab payload: (varint run length, value byte) pairs of maximal runs.
void encode_u8_slab(const DenseVolume<std::uint8_t>& volume, std::int64_t k, ByteBuffer& out) {
  const std::uint8_t* values = volume.slab(k);
  const std::size_t n = volume.slab_size();
  for (std::size_t i = 0; i < n;) {
    const std::size_t run = byte_run_length(values, i, n);
    out.put_varint(run);
    out.put_byte(values[i]);
    i += run;
  }
}

// f32 slab payload: (varint run length, 4 little-endian bytes) pairs of
// maximal runs of equal bit patterns (the spec compares bytes, not values).
void encode_f32_slab(const DenseVolume<float>& volume, std::int64_t k, ByteBuffer& out) {
  const float* values = volume.slab(k);
  const std::size_t n = volume.slab_size();
  for (std::size_t i = 0; i < n;) {
    const std::uint32_t bits = std::bit_cast<std::uint32_t>(values[i]);
    std::size_t j = i + 1;
    while (j < n && std::bit_cast<std::uint32_t>(values[j]) == bits) ++j;
    out.put_varint(j - i);
    for (int b = 0; b < 4; ++b) out.put_byte(static_cast<std::uint8_t>(bits >> (8 * b)));
    i = j;
  }
}

// rgba8 slab payload: (varint run length, r, g, b, a) pairs of maximal runs
// of equal colours (all four bytes equal, spec 5.2).
void encode_rgba8_slab(const DenseVolume<Rgba8>& volume, std::int64_t k, ByteBuffer& out) {
  const Rgba8* values = volume.slab(k);
  const std::size_t n = volume.slab_size();
  for (std::size_t i = 0; i < n;) {
    const Rgba8 c = values[i];
    std::size_t j = i + 1;
    while (j < n && values[j] == c) ++j;
    out.put_varint(j - i);
    out.put_byte(c.r);
    out.put_byte(c.g);
    out.put_byte(c.b);
    out.put_byte(c.a);
    i = j;
  }
}

// Levels of a quantized stream: value = offset + scale * q for q in 0..top;
// top + 1 marks NaN.
struct Quantizer {
  double offset = 0.0, scale = 1.0;
  std::uint32_t top = 0;
  std::uint32_t level(float v) const {
    if (std::isnan(v)) return top + 1;
    const double q = std::nearbyint((static_cast<double>(v) - offset) / scale);
    return q <= 0 ? 0 : q >= top ? top : static_cast<std::uint32_t>(q);
  }
};

Quantizer make_quantizer(const DenseVolume<float>& volume, std::uint32_t top) {
  double lo = INFINITY, hi = -INFINITY;
  for (float v : volume.values())
    if (std::isfinite(v)) {
      lo = std::min(lo, static_cast<double>(v));
      hi = std::max(hi, static_cast<double>(v));
    }
  if (!(lo <= hi)) lo = hi = 0.0;  // no finite value
  if (lo < 0 && hi > 0) hi = std::max(-lo, hi), lo = -hi;
  Quantizer q;
  q.top = top;
  q.offset = lo;
  q.scale = hi > lo ? (hi - lo) / top : 1.0;
  return q;
}

// Runs of equal levels, the levels little-endian in `bytes` bytes.
void encode_quantized_slab(const DenseVolume<float>& volume, std::int64_t k, const Quantizer& q, int bytes, ByteBuffer& out) {
  const float* values = volume.slab(k);
  const std::size_t n = volume.slab_size();
  for (std::size_t i = 0; i < n;) {
    const std::uint32_t level = q.level(values[i]);
    std::size_t j = i + 1;
    while (j < n && q.level(values[j]) == level) ++j;
    out.put_varint(j - i);
    for (int b = 0; b < bytes; ++b) out.put_byte(static_cast<std::uint8_t>(level >> (8 * b)));
    i = j;
  }
}

}  // namespace

void write_rle_quantized(const DenseVolume<float>& volume, Quantize levels, std::string_view content, ByteSink& sink) {
  if (levels == Quantize::none) throw Error(ErrorCode::invalid_argument, "write_rle_quantized needs u8 or u16 levels");
  encode::require_voxels(volume, "RLE writer");
  const int bytes = levels == Quantize::u8 ? 1 : 2;
  const Quantizer q = make_quantizer(volume, levels == Quantize::u8 ? 254u : 65534u);
  nlohmann::ordered_json meta;
  meta["quantization"] = {{"offset", q.offset}, {"scale", q.scale}, {"levels", q.top + 1}, {"nan_level", q.top + 1},
                          {"content", std::string(content)}};
  write_header(volume.grid(), bytes == 1 ? encode::RleValueType::u8 : encode::RleValueType::u16, sink, meta.dump());
  write_slab_blocks(
      volume.grid().dims.z, volume.slab_size() * sizeof(float),
      [&volume, &q, bytes](std::int64_t k, ByteBuffer& out) { encode_quantized_slab(volume, k, q, bytes, out); }, sink);
}

namespace encode {

void write_rle_bit_header(const Grid& grid, ByteSink& sink) { write_header(grid, RleValueType::bit, sink); }

void write_rle_bit_layers(const BitVolume& slab, std::int64_t k0, ByteSink& sink) {
  write_slab_block_range(
      k0, k0 + slab.grid().dims.z, slab.slab_words() * sizeof(std::uint64_t),
      [&slab, k0](std::int64_t k, ByteBuffer& out) { encode_bit_slab(slab, k - k0, out); }, sink);
}

void encode_rle_bit_layers(const RunSlab& slab, std::int64_t k0, std::vector<std::uint8_t>& out) {
  out.clear();
  ByteBuffer buffer;
  for (std::int64_t k = 0; k < slab.grid().dims.z; ++k) {
    buffer.reset(kBlockHeaderRoom);
    encode_run_layer(slab, k, buffer);
    const std::span<const std::uint8_t> block = finish_block(k0 + k, buffer);
    out.insert(out.end(), block.begin(), block.end());
  }
}

void write_rle_bit_layers(const RunSlab& slab, std::int64_t k0, ByteSink& sink) {
  // Encoded where the slab was made (prepare_rle_layer_blocks), the blocks
  // are only copied here, on the one thread that writes in order.
  if (const RunSlab::Prepared& ready = slab.prepared(); ready.k0 == k0) {
    sink.write(ready.bytes.data(), ready.bytes.size());
    return;
  }
  ByteBuffer buffer;
  for (std::int64_t k = 0; k < slab.grid().dims.z; ++k) {
    buffer.reset(kBlockHeaderRoom);
    encode_run_layer(slab, k, buffer);
    write_block(k0 + k, buffer, sink);
  }
}

void write_rle_end(std::int64_t nz, ByteSink& sink) { write_end_block(nz, sink); }

void write_rle_value_header(const ValueVolume& type, const Grid& grid, ByteSink& sink) {
  write_header(grid, *value_named(kRleValueTypeNames, std::string_view(value_type_name(type))), sink);
}

void write_rle_value_layers(const ValueVolume& slab, std::int64_t k0, ByteSink& sink) {
  std::visit(
      [&](const auto& v) {
        using T = std::decay_t<decltype(v.values()[0])>;
        write_slab_block_range(
            k0, k0 + v.grid().dims.z, v.slab_size() * sizeof(T),
            [&v, k0](std::int64_t k, ByteBuffer& out) {
              if constexpr (std::is_same_v<T, float>) encode_f32_slab(v, k - k0, out);
              else if constexpr (std::is_same_v<T, Rgba8>) encode_rgba8_slab(v, k - k0, out);
              else encode_u8_slab(v, k - k0, out);
            },
            sink);
      },
      slab);
}

}  // namespace encode

void write_rle(const DenseVolume<float>& volume, ByteSink& sink) {
  encode::require_voxels(volume, "RLE writer");
  write_header(volume.grid(), encode::RleValueType::f32, sink);
  write_slab_blocks(
      volume.grid().dims.z, volume.slab_size() * sizeof(float),
      [&volume](std::int64_t k, ByteBuffer& out) { encode_f32_slab(volume, k, out); }, sink);
}

void write_rle(const BitVolume& volume, ByteSink& sink) {
  encode::require_voxels(volume.grid(), "RLE writer");
  write_header(volume.grid(), encode::RleValueType::bit, sink);
  write_slab_blocks(
      volume.grid().dims.z, volume.slab_words() * sizeof(std::uint64_t),
      [&volume](std::int64_t k, ByteBuffer& out) { encode_bit_slab(volume, k, out); }, sink);
}

void write_rle(const DenseVolume<std::uint8_t>& volume, ByteSink& sink) {
  encode::require_voxels(volume, "RLE writer");
  write_header(volume.grid(), encode::RleValueType::u8, sink);
  write_slab_blocks(
      volume.grid().dims.z, volume.slab_size(),
      [&volume](std::int64_t k, ByteBuffer& out) { encode_u8_slab(volume, k, out); }, sink);
}

void write_rle(const DenseVolume<Rgba8>& volume, ByteSink& sink) {
  encode::require_voxels(volume, "RLE writer");
  write_header(volume.grid(), encode::RleValueType::rgba8, sink);
  write_slab_blocks(
      volume.grid().dims.z, volume.slab_size() * sizeof(Rgba8),
      [&volume](std::int64_t k, ByteBuffer& out) { encode_rgba8_slab(volume, k, out); }, sink);
}

}  // namespace voxd
