#pragma once
// Unsigned LEB128 varints: 7 bits per byte, least significant group first,
// high bit set on every byte but the last. Used for every length in the RLE
// stream because most runs are short (1 byte) yet a run may span a 2^32-voxel
// slab. A 64-bit value needs at most 10 bytes.
#include <cstddef>
#include <cstdint>

namespace voxd::encode {

inline constexpr std::size_t kMaxVarintBytes = 10;

// Writes v at p (which must have kMaxVarintBytes of room); returns the end.
inline std::uint8_t* put_varint(std::uint8_t* p, std::uint64_t v) {
  while (v >= 0x80) {
    *p++ = static_cast<std::uint8_t>(v | 0x80);
    v >>= 7;
  }
  *p++ = static_cast<std::uint8_t>(v);
  return p;
}

}  // namespace voxd::encode
