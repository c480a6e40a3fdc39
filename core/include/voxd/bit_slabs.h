#pragma once
// A bit volume handed on z-slab by z-slab: the shape every out-of-core stage
// shares (the streamed voxelizer produces it, the RLE slab reader replays a
// stored result as it, the slab writers and the streamed analyses consume
// it), so no stage ever needs the whole grid. A whole in-memory volume is the
// one-slab case: (0, volume).
#include <cstdint>
#include <functional>

#include "voxd/bit_volume.h"
#include "voxd/grid.h"

namespace voxd {

// Receives z layers [k0, k0 + slab.grid().dims.z) of the grid as a volume
// whose grid is that part of the whole one (its origin moved up by k0
// voxels). Called in z order, on the calling thread; the slab is reused after
// the call returns.
using BitSlabConsumer = std::function<void(std::int64_t k0, const BitVolume& slab)>;

// The grid's z layers [k0, k0 + layers), as a slab's grid.
inline Grid slab_grid(const Grid& grid, std::int64_t k0, std::int64_t layers) {
  Grid g = grid;
  g.origin.z += static_cast<double>(k0) * grid.voxel_size;
  g.dims.z = layers;
  return g;
}

}  // namespace voxd
