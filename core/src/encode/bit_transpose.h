#pragma once
// In-place transpose of a 64x64 bit matrix: afterwards bit r of a[c] is what
// bit c of a[r] was. binvox wants x as its slowest axis while BitVolume packs
// x into words; transposing 64x64 blocks turns a word column of the volume
// into 64 bit-packed x-slabs (y fastest) with ~400 word operations per 4096
// voxels, instead of one random bit access per voxel.
#include <cstdint>

namespace voxd::encode {

inline void transpose_64x64(std::uint64_t* a) {
  // Swap ever smaller off-diagonal blocks: 32x32, then 16x16 inside each, ...
  std::uint64_t mask = 0x00000000FFFFFFFFull;
  for (int j = 32; j != 0; j >>= 1, mask ^= mask << j) {
    for (int k = 0; k < 64; k = ((k | j) + 1) & ~j) {
      const std::uint64_t t = ((a[k] >> j) ^ a[k | j]) & mask;
      a[k | j] ^= t;
      a[k] ^= t << j;
    }
  }
}

}  // namespace voxd::encode
