#pragma once
// Conservative surface voxelization (surface_voxelizer.cpp) by z chunks: each
// chunk's voxels are final once it is filled and chunks touch disjoint z
// layers, so threads fill chunks concurrently and a streamed run fills a
// slab's chunks and hands the slab on.
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "voxd/bit_volume.h"
#include "voxd/mesh.h"

namespace voxd::detail {

class SurfaceVoxelizer {
 public:
  // `rows_per_chunk` 0: enough chunks to balance the threads over the grid.
  SurfaceVoxelizer(const Mesh& mesh, const Grid& grid, int threads, std::int64_t rows_per_chunk = 0);

  std::int64_t chunk_count() const { return static_cast<std::int64_t>(bins_.size()); }
  std::int64_t rows_per_chunk() const { return per_chunk_; }
  int threads() const { return threads_; }

  // ORs the surface voxels of z layers [chunk * rows_per_chunk, ...) into
  // `out`, which holds the grid's z layers from `z_origin` on.
  void fill_chunk(std::int64_t chunk, BitVolume& out, std::int64_t z_origin = 0) const;

  // The same voxels as spans of x-rows, for runs made without a volume:
  // `row` is (k - the chunk's first layer) * dims.y + j, voxels [begin, end).
  // In no particular order; spans may overlap and touch.
  struct RowSpan {
    std::uint32_t row, begin, end;
  };
  void chunk_spans(std::int64_t chunk, std::vector<RowSpan>& out) const;

 private:
  template <class Emit>
  void for_each_voxel(std::int64_t chunk, Emit&& emit) const;

  const Mesh* mesh_;
  Grid grid_;
  int threads_;
  std::int64_t per_chunk_ = 1;
  std::vector<glm::dvec3> unit_;  // vertices in voxel units
  std::vector<std::vector<std::uint32_t>> bins_;
};

}  // namespace voxd::detail
