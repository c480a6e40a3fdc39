#pragma once
// The z layers a streamed or run-making voxelization covers, and the chunk
// size that keeps every chunk inside them.
#include <cstdint>

#include "voxd/grid.h"
#include "voxd/voxelize/streamed.h"

namespace voxd::detail {

struct LayerChunks {
  std::int64_t first = 0, end = 0;  // layers [first, end)
  std::int64_t per_chunk = 1;       // chunk c is layers [c * per_chunk, ...)
  std::int64_t first_chunk() const { return first / per_chunk; }
  std::int64_t end_chunk() const { return (end + per_chunk - 1) / per_chunk; }
};

// `range` checked against the grid (Error(invalid_argument) off it), with
// chunks of at most `wanted` layers whose boundaries fall on both ends of the
// range (but the grid's last layer), so a chunk never reaches out of it.
LayerChunks layer_chunks(const Grid& grid, LayerRange range, std::int64_t wanted);

}  // namespace voxd::detail
