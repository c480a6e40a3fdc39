#pragma once
// Slab-streamed binary voxelization (Thon et al.'s "limited only by disk
// size"; Patil & Ravi's stack of voxel layers): the grid is voxelized z-slab
// by z-slab, each slab handed on (to an encoder, a file, an accumulator) as
// soon as it is final and its memory reused for the next. Peak memory is the
// mesh, its triangle bins and one slab, O(triangles + nx * ny * slab), not
// O(nx * ny * nz); the voxels are exactly voxelize()'s.
#include <cstdint>

#include "voxd/bit_slabs.h"
#include "voxd/bit_volume.h"
#include "voxd/mesh.h"
#include "voxd/progress.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd {

// Whether these options stream: the parity inside test (rays along x; the
// vote's rays along y and z, and the winding number's whole-mesh sums, do
// not), in every mode.
bool can_stream(const VoxelizeOptions& options);

// Z layers per slab for about `slab_bytes` of bits (at least one layer, at
// most the grid's).
std::int64_t streamed_slab_layers(const Grid& grid, std::uint64_t slab_bytes);

// Z layers [begin, end) of a grid: the part of it one streamed run makes
// (a slab task of a job spread over many workers). end < 0: to the last.
struct LayerRange {
  std::int64_t begin = 0, end = -1;
};

// Voxelizes slab by slab in z order, handing each slab to `consume`; only
// the layers of `range`, when given (bit for bit the whole run's: each row
// of voxels is made alone). Throws Error(invalid_argument) for options that
// do not stream (can_stream) or a range off the grid. Progress runs over
// the slabs (the consumer's work included); cancellation is honoured
// between slabs and between chunks of a slab.
void voxelize_streamed(const Mesh& mesh, const Grid& grid, const VoxelizeOptions& options, std::int64_t slab_layers,
                       const BitSlabConsumer& consume, JobControl* control = nullptr, LayerRange range = {});

}  // namespace voxd
