#pragma once
// Rows of runs (RunSlab rows: increasing bounds b0, e0, b1, e1, ...) compared
// with each other, for the analyses that read a stored volume as its runs:
// along a ray that crosses rows, a run begins where a voxel is in a row and
// not in the row before, and ends where it is not; those differences are
// found in a walk over both rows' runs, so they cost the runs and the
// changed voxels, never the row's bits.
#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

#include "voxd/run_slab.h"

namespace voxd::detail {

using Runs = std::span<const std::uint32_t>;

// Calls f(b, e) for each maximal range [b, e) of voxels in a's runs and not
// in b's.
template <typename F>
void for_each_difference(Runs a, Runs b, const F& f) {
  std::size_t y = 0;
  for (std::size_t x = 0; x < a.size(); x += 2) {
    std::uint32_t begin = a[x];
    const std::uint32_t end = a[x + 1];
    while (y < b.size() && b[y + 1] <= begin) y += 2;  // b's runs wholly before this one
    for (std::size_t z = y; begin < end; z += 2) {
      if (z >= b.size() || b[z] >= end) {
        f(begin, end);
        break;
      }
      if (b[z] > begin) f(begin, b[z]);
      begin = std::max(begin, b[z + 1]);
    }
  }
}

// The last `layers` layers of the slabs seen so far, as a slab of that many
// layers: those of `slab`, after those of `kept` (the last such copy) when
// the slab is thinner; empty rows for layers before the grid's first. A
// consumer of slabs keeps it for the rays that cross into the next slab.
inline RunSlab last_layers(const RunSlab& kept, const RunSlab& slab, std::int64_t layers) {
  const std::int64_t ny = slab.grid().dims.y, n = slab.grid().dims.z, kept_layers = kept.grid().dims.z;
  std::vector<Runs> rows;
  rows.reserve(static_cast<std::size_t>(ny * layers));
  for (std::int64_t l = n - layers; l < n; ++l)
    for (std::int64_t j = 0; j < ny; ++j)
      rows.push_back(l >= 0 ? slab.row(j, l) : kept_layers + l >= 0 ? kept.row(j, kept_layers + l) : Runs{});
  Grid grid = slab.grid();
  grid.dims.z = layers;
  RunSlab out(grid);
  for (const Runs row : rows) {
    for (std::size_t r = 0; r < row.size(); r += 2) out.add_run(row[r], row[r + 1]);
    out.end_row();
  }
  return out;
}

}  // namespace voxd::detail
