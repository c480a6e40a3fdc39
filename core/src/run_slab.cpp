#include "voxd/run_slab.h"

#include <algorithm>

#include "encode/bit_runs.h"
#include "voxd/parallel.h"

namespace voxd {

void RunSlab::reset(const Grid& grid) {
  grid_ = grid;
  starts_.clear();
  starts_.reserve(static_cast<std::size_t>(row_count()) + 1);
  starts_.push_back(0);
  bounds_.clear();
  filled_ = 0;
  prepared_.k0 = -1;
  prepared_.bytes.clear();
}

void RunSlab::free_on_every_thread(int threads) {
  voxd::free_on_every_thread(bounds_, threads);
  voxd::free_on_every_thread(starts_, threads);
  voxd::free_on_every_thread(prepared_.bytes, threads);
  *this = RunSlab();
}

void RunSlab::append_rows(const RunSlab& next) {
  const RunSlab* one[] = {&next};
  append_rows(one, 1);
}

void RunSlab::append_rows(std::span<const RunSlab* const> next, int threads) {
  prepared_.k0 = -1;
  // Where each one's bounds and row starts go. Sized once, then written on
  // any thread: a gathered batch of a large grid's layers is mostly copying
  // onto pages that are new, which one thread would do alone.
  std::vector<std::size_t> bounds_at(next.size() + 1, bounds_.size()), starts_at(next.size() + 1, starts_.size());
  for (std::size_t s = 0; s < next.size(); ++s) {
    bounds_at[s + 1] = bounds_at[s] + next[s]->bounds_.size();
    starts_at[s + 1] = starts_at[s] + next[s]->starts_.size() - 1;
    filled_ += next[s]->filled_;
  }
  bounds_.resize(bounds_at.back());
  starts_.resize(starts_at.back());
  parallel_for(0, static_cast<std::int64_t>(next.size()), 1, threads, [&](std::int64_t s0, std::int64_t s1) {
    for (auto s = static_cast<std::size_t>(s0); s < static_cast<std::size_t>(s1); ++s) {
      const RunSlab& from = *next[s];
      std::copy(from.bounds_.begin(), from.bounds_.end(), bounds_.begin() + static_cast<std::ptrdiff_t>(bounds_at[s]));
      const auto base = static_cast<std::uint32_t>(bounds_at[s]);
      std::uint32_t* out = starts_.data() + starts_at[s];
      const std::uint32_t* in = from.starts_.data() + 1;
      const std::size_t rows = from.starts_.size() - 1;
      for (std::size_t r = 0; r < rows; ++r) out[r] = base + in[r];
    }
  });
}

BitVolume RunSlab::to_bits() const {
  BitVolume bits(grid_);
  for (std::int64_t k = 0; k < grid_.dims.z; ++k)
    for (std::int64_t j = 0; j < grid_.dims.y; ++j) {
      const auto runs = row(j, k);
      for (std::size_t r = 0; r < runs.size(); r += 2) encode::set_bit_range(bits.row(j, k), runs[r], runs[r + 1]);
    }
  return bits;
}

RunSlab RunSlab::from_bits(const BitVolume& volume) {
  RunSlab slab(volume.grid());
  const std::int64_t nx = volume.grid().dims.x;
  for (std::int64_t k = 0; k < volume.grid().dims.z; ++k)
    for (std::int64_t j = 0; j < volume.grid().dims.y; ++j) {
      const std::uint64_t* row = volume.row(j, k);
      for (std::int64_t i = encode::next_different_bit(row, 0, nx, false); i < nx;) {
        const std::int64_t end = encode::next_different_bit(row, i, nx, true);
        slab.add_run(static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(end));
        i = end < nx ? encode::next_different_bit(row, end, nx, false) : nx;
      }
      slab.end_row();
    }
  return slab;
}

}  // namespace voxd
