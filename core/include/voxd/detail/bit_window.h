#pragma once
// The set voxels of the 5 x 5 x 5 window around a voxel, read once: a row
// of 5 bits (x - 2 to x + 2) for each of its 25 rows (y, z). Wall
// thickness fits a surface to every empty voxel on a wall's faces from the
// window around it (tens of lookups each, over a million fits on a CAD
// part at 256^3): one read a row instead of a bounds check and a lookup a
// voxel.
//
// Not part of the engine's API (for wall thickness and its tests).
#include <cstdint>

#include <glm/vec3.hpp>

#include "voxd/bit_volume.h"

namespace voxd::detail {

class BitWindow5 {
 public:
  BitWindow5(const BitVolume& volume, const glm::i64vec3& centre) {
    const glm::i64vec3 d = volume.grid().dims;
    const std::int64_t i0 = centre.x - 2;
    for (int z = -2; z <= 2; ++z)
      for (int y = -2; y <= 2; ++y) {
        std::uint32_t bits = 0;
        const std::int64_t j = centre.y + y, k = centre.z + z;
        if (j >= 0 && k >= 0 && j < d.y && k < d.z) {
          const std::uint64_t* row = volume.row(j, k);
          if (i0 >= 0 && i0 + 4 < d.x) {  // the five bits at once, from one word or two
            const std::int64_t w = i0 >> 6, shift = i0 & 63;
            std::uint64_t v = row[w] >> shift;
            if (shift > 59) v |= row[w + 1] << (64 - shift);
            bits = static_cast<std::uint32_t>(v & 31u);
          } else {  // by the grid's x edges: bit by bit, nothing outside
            for (int x = 0; x < 5; ++x) {
              const std::int64_t i = i0 + x;
              if (i >= 0 && i < d.x && ((row[i >> 6] >> (i & 63)) & 1u)) bits |= 1u << x;
            }
          }
        }
        rows_[(z + 2) * 5 + (y + 2)] = bits;
      }
  }
  // Row (z + 2) * 5 + (y + 2), bit x + 2: whether centre + (x, y, z) is
  // set (outside the grid nothing is).
  bool get(int row, int bit) const { return (rows_[row] >> bit) & 1u; }
  bool get(int x, int y, int z) const { return get((z + 2) * 5 + (y + 2), x + 2); }

 private:
  std::uint32_t rows_[25];
};

}  // namespace voxd::detail
