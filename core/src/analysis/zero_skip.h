#pragma once
// Skipping the empty voxels of a value map (a thickness map is 0 outside the
// part, most of a padded grid): eight at a time while all eight are +0.0,
// which no statistic or region counts, instead of a compare and a branch
// each.
#include <cstdint>
#include <cstring>

namespace voxd::detail {

// The first i' >= i (and <= n) from which the floats are not all +0.0 in
// the next block of eight; i' - i is a multiple of 8 or i' = n.
inline std::int64_t skip_zero_blocks(const float* v, std::int64_t i, std::int64_t n) {
  while (i + 8 <= n) {
    std::uint64_t w[4];
    std::memcpy(w, v + i, sizeof w);
    if ((w[0] | w[1] | w[2] | w[3]) != 0) break;
    i += 8;
  }
  return i;
}

}  // namespace voxd::detail
