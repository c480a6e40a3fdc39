#pragma once
// A z-slab of a bit volume as the filled runs of its x-rows. The parity
// voxelizer finds each row's crossings in order along the row, so the runs
// are what it knows; an output made of runs (voxd's RLE) is written from
// them without a dense volume ever being filled and scanned again. Memory is
// proportional to the runs, not to the voxels: at 1024^3 a slab of 16 layers
// of the benchmark torus holds about 40 thousand runs where its bits take 2 MB.
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "voxd/bit_volume.h"
#include "voxd/grid.h"
#include "voxd/uncleared_vector.h"

namespace voxd {

class RunSlab {
 public:
  RunSlab() = default;
  // A slab of `grid` (its dims.z layers) with no row started.
  explicit RunSlab(const Grid& grid) { reset(grid); }

  const Grid& grid() const { return grid_; }
  std::int64_t row_count() const { return grid_.dims.y * grid_.dims.z; }

  // Row (j, k) of the slab: the filled runs as bounds b0, e0, b1, e1, ...
  // (voxels [b, e) along x), increasing, disjoint and not touching, so each
  // pair is a maximal run.
  std::span<const std::uint32_t> row(std::int64_t j, std::int64_t k) const {
    const auto r = static_cast<std::size_t>(k * grid_.dims.y + j);
    return {bounds_.data() + starts_[r], bounds_.data() + starts_[r + 1]};
  }

  // Building, rows in order (j fastest, then k): add_run for each run of the
  // row (increasing, separated by at least one empty voxel), then end_row.
  void reset(const Grid& grid);
  void add_run(std::uint32_t begin, std::uint32_t end) {
    bounds_.push_back(begin);
    bounds_.push_back(end);
    filled_ += end - begin;
  }
  void end_row() { starts_.push_back(static_cast<std::uint32_t>(bounds_.size())); }
  // Room for `runs` runs before the slab's memory grows (and is copied
  // whole). Room not written is address space, not memory.
  void reserve_runs(std::size_t runs) { bounds_.reserve(2 * runs); }
  // Ends the slab after its first `layers` layers, whose rows are all
  // built: a slab handed on before its grid's last layer.
  void set_layers(std::int64_t layers) {
    grid_.dims.z = layers;
    prepared_.k0 = -1;
  }
  // Appends the rows of `next`, a slab of the layers after this one's rows
  // (a whole grid's runs gathered slab by slab).
  void append_rows(const RunSlab& next);
  // Appends the rows of each of `next` in turn, as many append_rows calls
  // would, copying them on up to `threads` threads (0: every core): only
  // where each one goes is summed in order.
  void append_rows(std::span<const RunSlab* const> next, int threads);

  // Frees the slab's memory, its pages given back on up to `threads`
  // threads (free_on_every_thread in voxd/uncleared_vector.h); the slab is
  // then empty, of no grid.
  void free_on_every_thread(int threads);

  std::uint64_t count() const { return filled_; }
  std::size_t run_count() const { return bounds_.size() / 2; }

  // The same voxels as a bit volume of the slab's grid; and the runs of one
  // (tests, and outputs that are not made of runs).
  BitVolume to_bits() const;
  static RunSlab from_bits(const BitVolume& volume);

  // What a RunSlabPreparer made of the slab for the consumer it comes with
  // (a writer's encoded bytes), and the grid layer k0 it was made at. The
  // slab's rows must not change after it; reset() and the other changes of
  // its layers drop it.
  struct Prepared {
    std::int64_t k0 = -1;
    std::vector<std::uint8_t> bytes;
  };
  Prepared& prepared() { return prepared_; }
  const Prepared& prepared() const { return prepared_; }

 private:
  // resize() leaves the new elements to be written (append_rows writes
  // each on the thread that copies it) rather than clearing them all on the
  // calling thread first.
  using Bounds = UnclearedVector<std::uint32_t>;

  Grid grid_;
  Bounds starts_;  // row r's bounds are [starts_[r], starts_[r + 1])
  Bounds bounds_;
  std::uint64_t filled_ = 0;
  Prepared prepared_;
};

// Receives z layers [k0, k0 + slab.grid().dims.z) of the grid as runs, as a
// BitSlabConsumer does bits (voxd/bit_slabs.h): in z order, on the calling
// thread; the slab is reused after the call returns.
using RunSlabConsumer = std::function<void(std::int64_t k0, const RunSlab& slab)>;

// Work a consumer hands to the threads that make the slabs, done on each
// slab as soon as it is made, in parallel and in any order, before the
// consumer takes it in z order: what it makes goes in slab.prepared() (a
// writer's encoding, so that only copying the bytes is left to the one
// thread that writes in order).
using RunSlabPreparer = std::function<void(std::int64_t k0, RunSlab& slab)>;

}  // namespace voxd
