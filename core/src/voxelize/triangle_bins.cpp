#include "voxelize/triangle_bins.h"

#include <algorithm>

#include "voxd/error.h"
#include "voxd/parallel.h"

namespace voxd::detail {

TriangleBins bin_triangles(const FixedMesh& mesh, int axis, std::int64_t rows, std::int64_t rows_per_chunk,
                           std::int64_t margin, int threads) {
  TriangleBins bins;
  bins.rows_per_chunk = rows_per_chunk;
  bins.chunk_count = (rows + rows_per_chunk - 1) / rows_per_chunk;
  const auto& tris = mesh.triangles();
  const auto n = static_cast<std::int64_t>(tris.size());

  // Chunk range of each triangle, computed in parallel; -1 marks "none".
  std::vector<std::int32_t> first(static_cast<std::size_t>(n)), last(static_cast<std::size_t>(n));
  parallel_for(0, n, 1 << 15, threads, [&](std::int64_t b, std::int64_t e) {
    for (std::int64_t t = b; t < e; ++t) {
      const auto& tri = tris[static_cast<std::size_t>(t)];
      const std::int64_t a = mesh.vertex(tri[0])[axis], bb = mesh.vertex(tri[1])[axis],
                         c = mesh.vertex(tri[2])[axis];
      const std::int64_t r0 = std::max<std::int64_t>(0, ceil_fixed(std::min({a, bb, c})) - margin);
      const std::int64_t r1 = std::min<std::int64_t>(rows - 1, floor_fixed(std::max({a, bb, c})) + margin);
      if (r0 > r1) {
        first[t] = -1;
        last[t] = -2;
      } else {
        first[t] = static_cast<std::int32_t>(r0 / rows_per_chunk);
        last[t] = static_cast<std::int32_t>(r1 / rows_per_chunk);
      }
    }
  });

  // Counting sort into chunks (single pass over small integers: cheap).
  std::vector<std::uint64_t> counts(static_cast<std::size_t>(bins.chunk_count) + 1, 0);
  for (std::int64_t t = 0; t < n; ++t)
    for (std::int32_t c = first[t]; c <= last[t]; ++c) ++counts[static_cast<std::size_t>(c) + 1];
  for (std::size_t c = 1; c < counts.size(); ++c) counts[c] += counts[c - 1];
  if (counts.back() > 0xFFFFFFFFull)
    throw Error(ErrorCode::limit_exceeded, "too many triangle/slab pairs; use a coarser grid or fewer triangles");
  bins.offsets.assign(counts.begin(), counts.end());
  bins.triangles.resize(counts.back());
  std::vector<std::uint32_t> cursor(bins.offsets.begin(), bins.offsets.end() - 1);
  for (std::int64_t t = 0; t < n; ++t)
    for (std::int32_t c = first[t]; c <= last[t]; ++c) bins.triangles[cursor[static_cast<std::size_t>(c)]++] = static_cast<std::uint32_t>(t);
  return bins;
}

}  // namespace voxd::detail
