#pragma once
// Finding runs in a bit row (LSB of word 0 = first voxel), 64 voxels per step:
// the encoders turn bit-packed rows into run lengths without visiting voxels
// one by one, which is what keeps a 1024^3 volume well under 0.1 s.
#include <algorithm>
#include <bit>
#include <cstdint>

namespace voxd::encode {

// First index in [from, n) whose bit differs from `value`, or n if none.
// Bits at or past n are never looked at as voxels (they may hold anything).
inline std::int64_t next_different_bit(const std::uint64_t* row, std::int64_t from, std::int64_t n, bool value) {
  const std::uint64_t flip = value ? ~std::uint64_t{0} : 0;
  const std::int64_t words = (n + 63) >> 6;
  std::int64_t w = from >> 6;
  std::uint64_t diff = (row[w] ^ flip) & (~std::uint64_t{0} << (from & 63));
  while (diff == 0) {
    if (++w >= words) return n;
    diff = row[w] ^ flip;
  }
  return std::min(n, (w << 6) + std::countr_zero(diff));
}

// Calls on_run(length) for each maximal run of equal bits in rows of n bits,
// continuing runs across consecutive calls; the first run is of 0s and may be
// empty. The caller ends the sequence with finish().
class BitRunSplitter {
 public:
  template <class OnRun>
  void add_row(const std::uint64_t* row, std::int64_t n, OnRun&& on_run) {
    std::int64_t i = 0;
    while (i < n) {
      const std::int64_t next = next_different_bit(row, i, n, value_);
      run_ += static_cast<std::uint64_t>(next - i);
      i = next;
      if (i < n) {
        on_run(value_, run_);
        run_ = 0;
        value_ = !value_;
      }
    }
  }
  // Adds n voxels of 0 (padding).
  template <class OnRun>
  void add_zeros(std::uint64_t n, OnRun&& on_run) {
    if (n == 0) return;
    if (value_) {
      on_run(value_, run_);
      run_ = 0;
      value_ = false;
    }
    run_ += n;
  }
  // Emits the last, still open run.
  template <class OnRun>
  void finish(OnRun&& on_run) {
    on_run(value_, run_);
    run_ = 0;
    value_ = false;
  }

 private:
  bool value_ = false;
  std::uint64_t run_ = 0;
};

// Sets bits [begin, end) of a row (begin < end).
inline void set_bit_range(std::uint64_t* row, std::int64_t begin, std::int64_t end) {
  const std::int64_t wb = begin >> 6;
  const std::int64_t we = (end - 1) >> 6;
  const std::uint64_t first = ~std::uint64_t{0} << (begin & 63);
  const std::uint64_t last = ~std::uint64_t{0} >> (63 - ((end - 1) & 63));
  if (wb == we) {
    row[wb] |= first & last;
    return;
  }
  row[wb] |= first;
  std::fill(row + wb + 1, row + we, ~std::uint64_t{0});
  row[we] |= last;
}

}  // namespace voxd::encode
