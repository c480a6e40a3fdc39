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
  const auto chunks = static_cast<std::size_t>(bins.chunk_count);

  // A row's chunk from a table: a 64-bit division per corner cost more than
  // the rest of the binning.
  std::vector<std::int32_t> chunk_of_row(static_cast<std::size_t>(std::max<std::int64_t>(rows, 1)));
  for (std::int64_t r = 0; r < rows; ++r) chunk_of_row[static_cast<std::size_t>(r)] = static_cast<std::int32_t>(r / rows_per_chunk);

  // The triangles in `parts` consecutive ranges, each binned by one thread:
  // the chunk range of each triangle (first > last: none), then the counts
  // per range and chunk, so each range places its triangles at its own
  // offsets and every bin keeps the triangles in increasing order.
  const int parts = std::max(1, std::min<int>(threads > 0 ? threads : default_thread_count(),
                                              static_cast<int>(std::max<std::int64_t>(1, n >> 15))));
  const auto part_begin = [&](std::int64_t p) { return n * p / parts; };
  std::vector<std::int32_t> first(static_cast<std::size_t>(n)), last(static_cast<std::size_t>(n));
  std::vector<std::uint64_t> counts(static_cast<std::size_t>(parts) * chunks, 0);
  parallel_for(0, parts, 1, parts, [&](std::int64_t p0, std::int64_t p1) {
    for (std::int64_t p = p0; p < p1; ++p) {
      std::uint64_t* count = counts.data() + static_cast<std::size_t>(p) * chunks;
      for (std::int64_t t = part_begin(p); t < part_begin(p + 1); ++t) {
        const auto& tri = tris[static_cast<std::size_t>(t)];
        const std::int64_t a = mesh.coordinate(tri[0], axis), bb = mesh.coordinate(tri[1], axis),
                           c = mesh.coordinate(tri[2], axis);
        const std::int64_t r0 = std::max<std::int64_t>(0, ceil_fixed(std::min({a, bb, c})) - margin);
        const std::int64_t r1 = std::min<std::int64_t>(rows - 1, floor_fixed(std::max({a, bb, c})) + margin);
        if (r0 > r1) {
          first[t] = 0;
          last[t] = -1;
          continue;
        }
        first[t] = chunk_of_row[static_cast<std::size_t>(r0)];
        last[t] = chunk_of_row[static_cast<std::size_t>(r1)];
        for (std::int32_t ch = first[t]; ch <= last[t]; ++ch) ++count[ch];
      }
    }
  });

  // Offsets: chunk by chunk, and within a chunk range by range.
  bins.offsets.assign(chunks + 1, 0);
  std::vector<std::uint64_t> cursor(counts.size());
  std::uint64_t total = 0;
  for (std::size_t ch = 0; ch < chunks; ++ch) {
    bins.offsets[ch] = static_cast<std::uint32_t>(std::min<std::uint64_t>(total, 0xFFFFFFFFull));
    for (int p = 0; p < parts; ++p) {
      const std::size_t i = static_cast<std::size_t>(p) * chunks + ch;
      cursor[i] = total;
      total += counts[i];
    }
  }
  if (total > 0xFFFFFFFFull)
    throw Error(ErrorCode::limit_exceeded, "too many triangle/slab pairs; use a coarser grid or fewer triangles");
  bins.offsets[chunks] = static_cast<std::uint32_t>(total);
  bins.triangles.resize(total);
  parallel_for(0, parts, 1, parts, [&](std::int64_t p0, std::int64_t p1) {
    for (std::int64_t p = p0; p < p1; ++p) {
      std::uint64_t* at = cursor.data() + static_cast<std::size_t>(p) * chunks;
      for (std::int64_t t = part_begin(p); t < part_begin(p + 1); ++t)
        for (std::int32_t ch = first[t]; ch <= last[t]; ++ch) bins.triangles[at[ch]++] = static_cast<std::uint32_t>(t);
    }
  });
  return bins;
}

}  // namespace voxd::detail
