#pragma once
// Raw voxels as they arrive (streamed voxelization): one byte a voxel, or a
// continuous little-endian bit stream whose packer carries the partial byte
// from one slab to the next, so the bytes equal write_raw's.
#include <cstdint>

#include "encode/byte_buffer.h"
#include "voxd/bit_volume.h"
#include "voxd/byte_sink.h"

namespace voxd::encode {

// Appends bit fields to a little-endian bit stream.
class BitPacker {
 public:
  // Appends the low n bits of `bits` (1 <= n <= 64; higher bits zero).
  void put(std::uint64_t bits, int n) {
    pending_ |= bits << pending_bits_;
    if (pending_bits_ + n < 64) {
      pending_bits_ += n;
      return;
    }
    store(pending_, 8);
    pending_ = pending_bits_ == 0 ? 0 : bits >> (64 - pending_bits_);
    pending_bits_ = pending_bits_ + n - 64;
  }
  // Writes the complete bytes so far; with `last`, also the partial tail
  // byte (zero-padded).
  void flush(ByteSink& sink, bool last) {
    if (last && pending_bits_ > 0) {
      store(pending_, (pending_bits_ + 7) / 8);
      pending_ = 0;
      pending_bits_ = 0;
    }
    sink.write(out_.bytes());
    out_.reset();
  }
  std::size_t buffered() const { return out_.size(); }

 private:
  void store(std::uint64_t v, int bytes) {
    std::uint8_t le[8];
    for (int b = 0; b < 8; ++b) le[b] = static_cast<std::uint8_t>(v >> (8 * b));
    out_.put_bytes(le, static_cast<std::size_t>(bytes));
  }
  ByteBuffer out_;
  std::uint64_t pending_ = 0;
  int pending_bits_ = 0;
};

// Appends the volume's voxels, x fastest, to the packer's stream (writing
// whole megabytes to the sink as they fill); flush(sink, true) ends it.
void pack_raw_bits(const BitVolume& volume, BitPacker& packer, ByteSink& sink);
// One byte (0 or 1) a voxel, x fastest.
void write_raw_bytes(const BitVolume& volume, ByteSink& sink);

}  // namespace voxd::encode
