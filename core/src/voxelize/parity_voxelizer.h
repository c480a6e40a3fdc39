#pragma once
// Solid voxelization by ray parity (Thon, Gesquiere, Raffin 2004; Patil & Ravi
// 2005): one ray per voxel column along `ray_axis`; a voxel is inside iff an
// odd number of surface crossings lie before its centre.
//
// Instead of sorting crossings per column, each crossing toggles one bit (the
// first voxel it affects) in the output, and a prefix XOR along the ray turns
// toggles into filled runs. Work is split into chunks of rows on a partition
// axis; a chunk's output is final as soon as the chunk is done, so volumes can
// be produced slab by slab.
#include <cstdint>
#include <vector>

#include "voxd/bit_volume.h"
#include "voxd/mesh.h"
#include "voxd/progress.h"
#include "voxelize/column_scan.h"
#include "voxelize/fixed_point_mesh.h"
#include "voxelize/triangle_bins.h"

namespace voxd::detail {

class ParityVoxelizer {
 public:
  // `rows_per_chunk` 0 picks enough chunks to balance the threads over the
  // whole grid; a streamed run picks fewer rows, to balance them in a slab.
  ParityVoxelizer(const Mesh& mesh, const Grid& grid, int ray_axis, int threads, std::int64_t rows_per_chunk = 0);

  std::int64_t chunk_count() const { return bins_.chunk_count; }
  // Rows [chunk * rows_per_chunk, ...) of the partition axis.
  std::int64_t rows_per_chunk() const { return bins_.rows_per_chunk; }
  int partition_axis() const { return axes_.v; }

  // Writes the final voxels of one chunk into `volume` (which must be zero
  // there). Chunks may run concurrently: they touch disjoint words. With rays
  // along x or y, `volume` may hold only the z layers from `z_origin` on (a
  // slab of the grid, as streamed voxelization fills them).
  void fill_chunk(std::int64_t chunk, BitVolume& volume, std::int64_t z_origin = 0) const;

  // The crossings of one chunk's rows, for runs made without a volume (rays
  // along x only): `row` is (k - the chunk's first layer) * dims.y + j, `x`
  // the first voxel whose state the crossing flips (0 for one before the
  // grid; one past the grid is left out). In no particular order; a voxel is
  // filled iff an odd number of its row's crossings have x at or before it.
  struct RowCrossing {
    std::uint32_t row, x;
  };
  void chunk_crossings(std::int64_t chunk, std::vector<RowCrossing>& out) const;

  // All chunks, in parallel, honouring cancellation and reporting progress
  // in [progress_from, progress_to].
  void fill(BitVolume& volume, JobControl* control, double progress_from = 0.0, double progress_to = 1.0) const;

 private:
  template <class Emit>
  void for_each_crossing(std::int64_t chunk, Emit&& emit) const;

  Grid grid_;
  ScanAxes axes_;
  int threads_;
  FixedMesh fixed_;
  TriangleBins bins_;
};

}  // namespace voxd::detail
