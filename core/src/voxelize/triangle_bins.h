#pragma once
// Triangles binned by the row chunks (ranges of the partition axis) they can
// touch, so threads can each own a chunk of the output without locks.
#include <cstdint>
#include <vector>

#include "voxelize/fixed_point_mesh.h"

namespace voxd::detail {

struct TriangleBins {
  std::int64_t rows_per_chunk = 1;
  std::int64_t chunk_count = 0;
  std::vector<std::uint32_t> offsets;    // chunk c: triangles[offsets[c], offsets[c+1])
  std::vector<std::uint32_t> triangles;  // triangle indices
};

// A triangle goes to every chunk that holds a row centre within its extent on
// `axis` (extent rounded outward by `margin` voxels, for conservative tests).
TriangleBins bin_triangles(const FixedMesh& mesh, int axis, std::int64_t rows, std::int64_t rows_per_chunk,
                           std::int64_t margin, int threads);

}  // namespace voxd::detail
