#include "voxd/run_slab.h"

#include "encode/bit_runs.h"

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

void RunSlab::append_rows(const RunSlab& next) {
  prepared_.k0 = -1;
  const auto base = static_cast<std::uint32_t>(bounds_.size());
  bounds_.insert(bounds_.end(), next.bounds_.begin(), next.bounds_.end());
  // Sized first, then written: a loop of push_backs would check the
  // capacity for each row.
  const std::size_t rows = next.starts_.size() - 1, at = starts_.size();
  starts_.resize(at + rows);
  std::uint32_t* out = starts_.data() + at;
  const std::uint32_t* in = next.starts_.data() + 1;
  for (std::size_t r = 0; r < rows; ++r) out[r] = base + in[r];
  filled_ += next.filled_;
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
