#pragma once
// The runs of set bits (or, with `invert`, clear bits) of one bit-packed row
// of `dims_x` voxels, found a word at a time with count-trailing-zeros:
// on_run(begin, end) for each, [begin, end) along x, in order. Shared by the
// analyses that work on runs (parts and voids, mass properties).
#include <bit>
#include <cstdint>

namespace voxd::detail {

template <class OnRun>
void for_each_row_run(const std::uint64_t* row, std::int64_t words, std::int64_t dims_x, bool invert, const OnRun& on_run) {
  std::int64_t start = -1;
  for (std::int64_t w = 0; w < words; ++w) {
    std::uint64_t bits = invert ? ~row[w] : row[w];
    if (w == words - 1 && (dims_x & 63)) bits &= (std::uint64_t{1} << (dims_x & 63)) - 1;
    int pos = 0;
    while (pos < 64) {
      if (start < 0) {
        const std::uint64_t rest = bits >> pos;
        if (!rest) break;
        pos += std::countr_zero(rest);
        start = w * 64 + pos;
      } else {
        const std::uint64_t rest = ~bits >> pos;
        if (!rest) break;
        pos += std::countr_zero(rest);
        on_run(start, w * 64 + pos);
        start = -1;
      }
    }
  }
  if (start >= 0) on_run(start, dims_x);
}

}  // namespace voxd::detail
