#pragma once
// Rays along x at arbitrary places inside the voxel columns of one row: the
// exact crossings of one triangle with them. Shared by the coverage
// voxelizer (k x k rays per column) and the palette voxelizer (t random rays
// per column).
//
// Exactness: ray positions are fixed-point (voxelize/fixed_point_mesh.h)
// and tested against the triangle as voxelize/ray_triangle.h says, so a ray
// through a shared edge or vertex of a closed mesh crosses it exactly once.
#include <algorithm>
#include <atomic>
#include <cstdint>
#include <vector>

#include "voxd/grid.h"
#include "voxd/parallel.h"
#include "voxd/progress.h"
#include "voxelize/fixed_point_mesh.h"
#include "voxelize/ray_triangle.h"
#include "voxelize/triangle_bins.h"

namespace voxd::detail {

// A ray of one column crossing the surface: x in voxel units (voxel i spans
// [i, i + 1) along the ray axis).
struct RayCrossing {
  std::int32_t column;  // j, along y
  std::int32_t ray;     // the ray's index within its column
  double x;
};

// Sorts a row's crossings by column, then ray, then x.
inline void sort_crossings(std::vector<RayCrossing>& crossings) {
  std::sort(crossings.begin(), crossings.end(), [](const RayCrossing& a, const RayCrossing& b) {
    return a.column != b.column ? a.column < b.column : a.ray != b.ray ? a.ray < b.ray : a.x < b.x;
  });
}

// Appends the crossings of triangle `t` with the rays of row k in columns
// [j_begin, j_end) (`rays` rays each). position(j, r, pu, pv) gives ray r of column
// j in fixed point (u = y, v = z); every ray must lie within half a voxel
// of its column's centre line, i.e. in [j - 1/2, j + 1/2) x [k - 1/2, k + 1/2).
template <typename RayPosition>
void cross_row_rays(const FixedMesh& fixed, std::uint32_t t, std::int64_t k, std::int64_t j_begin, std::int64_t j_end,
                    int rays, const RayPosition& position, std::vector<RayCrossing>& out) {
  const auto& tri = fixed.triangles()[t];
  const FixedPoint A = fixed.vertex(tri[0]), B = fixed.vertex(tri[1]), C = fixed.vertex(tri[2]);
  RayTriangle triangle;
  std::int64_t j0, j1;
  if (!make_ray_triangle(A.data(), B.data(), C.data(), triangle) || !row_columns(triangle, k, j_begin, j_end, j0, j1))
    return;
  plane(triangle);
  for (std::int64_t j = j0; j <= j1; ++j)
    for (int r = 0; r < rays; ++r) {
      std::int64_t pu, pv;
      position(j, r, pu, pv);
      double x;
      if (cross_ray(triangle, pu, pv, x)) out.push_back({static_cast<std::int32_t>(j), r, x});
    }
}

// Rows of rays along z, their triangles binned once by chunks of rows, run
// over any range of whole chunks: the whole grid at once, or slab by slab
// (streamed coverage). Each row's crossings are the same whatever the range
// or the chunking: the triangles of its chunk that reach it, sorted.
class RayRows {
 public:
  // `rows_per_chunk` 0: enough chunks to balance `threads` over the grid.
  // `column_blocks`: the consumer takes any subset of a row's columns (see
  // run()); false hands it whole rows only.
  RayRows(const FixedMesh& fixed, const Grid& grid, int rays, int threads, std::int64_t rows_per_chunk = 0,
          bool column_blocks = false)
      : fixed_(fixed), grid_(grid), rays_(rays), threads_(threads), column_blocks_(column_blocks),
        per_chunk_(rows_per_chunk > 0 ? rows_per_chunk : std::max<std::int64_t>(1, grid.dims.z / (threads * 8))),
        // Rays of row k sit within half a voxel of its centre: margin 1.
        bins_(bin_triangles(fixed, 2, grid.dims.z, per_chunk_, 1, threads)) {}

  std::int64_t rows_per_chunk() const { return per_chunk_; }

  // Rows [k0, k1) (k0 a multiple of rows_per_chunk()), on the threads that
  // each own a chunk: the sorted crossings of row k's rays (`rays` per
  // column) with the mesh. prepare(k, scratch) returns row k's ray positions
  // (as cross_row_rays wants them); consume(k, crossings, scratch) uses the
  // crossings. Scratch is per thread. With column_blocks and fewer rows
  // than threads (a slab of a layer or two of a huge grid) each row goes in
  // blocks of columns, so that every thread has work: consume then gets a
  // block's crossings at a time, and blocks of one row may run at once (they
  // touch other columns).
  // Reports progress by columns of the grid and honours cancellation when
  // `control` is given.
  template <typename Scratch, typename Prepare, typename Consume>
  void run(std::int64_t k0, std::int64_t k1, JobControl* control, const Prepare& prepare, const Consume& consume) const {
    const std::int64_t ny = grid_.dims.y, rows = k1 - k0;
    const std::int64_t blocks =
        !column_blocks_ || rows <= 0 ? 1 : std::clamp<std::int64_t>((2 * threads_ + rows - 1) / rows, 1, std::max<std::int64_t>(ny / 8, 1));
    const auto columns = [&](std::int64_t k, std::int64_t j_begin, std::int64_t j_end, Scratch& scratch,
                             std::vector<RayCrossing>& crossings) {
      if (control) control->check_cancelled();
      const auto position = prepare(k, scratch);
      crossings.clear();
      const auto chunk = static_cast<std::size_t>(k / per_chunk_);
      for (std::uint32_t t = bins_.offsets[chunk]; t < bins_.offsets[chunk + 1]; ++t)
        cross_row_rays(fixed_, bins_.triangles[t], k, j_begin, j_end, rays_, position, crossings);
      sort_crossings(crossings);
      consume(k, crossings, scratch);
      const std::int64_t done = columns_done_ += j_end - j_begin;
      if (control) control->set_progress(static_cast<double>(done) / static_cast<double>(grid_.dims.z * ny));
    };
    if (blocks == 1) {
      parallel_for(k0, k1, per_chunk_, threads_, [&](std::int64_t a, std::int64_t b) {
        Scratch scratch;
        std::vector<RayCrossing> crossings;
        for (std::int64_t k = a; k < b; ++k) columns(k, 0, ny, scratch, crossings);
      });
      return;
    }
    parallel_for(0, rows * blocks, 1, threads_, [&](std::int64_t a, std::int64_t b) {
      Scratch scratch;
      std::vector<RayCrossing> crossings;
      for (std::int64_t item = a; item < b; ++item) {
        const std::int64_t block = item % blocks;
        columns(k0 + item / blocks, ny * block / blocks, ny * (block + 1) / blocks, scratch, crossings);
      }
    });
  }

 private:
  const FixedMesh& fixed_;
  Grid grid_;
  int rays_;
  int threads_;
  bool column_blocks_;
  std::int64_t per_chunk_;
  TriangleBins bins_;
  mutable std::atomic<std::int64_t> columns_done_{0};
};

// Every row of the grid: RayRows::run over [0, nz).
template <typename Scratch, typename Prepare, typename Consume>
void for_each_ray_row(const FixedMesh& fixed, const Grid& grid, int rays, int threads, JobControl* control,
                      const Prepare& prepare, const Consume& consume) {
  RayRows(fixed, grid, rays, threads).run<Scratch>(0, grid.dims.z, control, prepare, consume);
}

}  // namespace voxd::detail
