#pragma once
// Grey coverage (voxd/voxelize/coverage.h) in the shape a GPU computes it,
// written once for the CUDA kernels (core/src/cuda/coverage_kernel.cu) and
// for their host emulation (coverage_gpu.cpp), which the tests run on
// machines without a GPU:
//  1. for each row of a slab and each triangle binned to it, the crossings of
//     the row's rays with the triangle (cross_row_triangle), counted per
//     column, then written into each column's segment of one array;
//  2. for each column, its segment sorted by (ray, x), paired into run
//     events, sorted by (x, delta) and integrated (fill_coverage_column).
// The ray places, the crossing test and the integration are the CPU's own
// code (coverage.cpp uses coverage_ray_position too), so every float equals
// the CPU's: a column's crossings arrive in any order, but sorting by a
// total order over their values gives the CPU's sequence.
#include <math.h>

#include <cstdint>

#include "voxelize/coverage_runs.h"
#include "voxelize/fixed_point.h"
#include "voxelize/host_device.h"
#include "voxelize/ray_triangle.h"
#include "voxelize/splitmix.h"

namespace voxd::detail {

// Where the k x k rays of a column lie.
struct CoverageRayPattern {
  int k = 1;
  bool stochastic = false;
  std::uint64_t seed = 1;
  std::int64_t regular[64]{};  // fixed-point offsets (a + 1/2) / k - 1/2 voxel
};

// Ray (a, b) of column j, row k, in fixed point (u = y, v = z): on the
// regular pattern, or (stochastic) at a place hashed from the seed and the
// ray, within the column's cell (a, b).
VOXD_HD inline void coverage_ray_position(const CoverageRayPattern& p, std::int64_t j, std::int64_t k, int a, int b,
                                          std::int64_t& pu, std::int64_t& pv) {
  if (!p.stochastic) {
    pu = j * kFixedOne + p.regular[a];
    pv = k * kFixedOne + p.regular[b];
    return;
  }
  const std::uint64_t ray = static_cast<std::uint64_t>(k) << 20 ^ static_cast<std::uint64_t>(a * p.k + b);
  const std::uint64_t h =
      splitmix_hash(p.seed ^ splitmix_hash(static_cast<std::uint64_t>(j) * 0x100000001b3ull ^ splitmix_hash(ray)));
  const double one = static_cast<double>(kFixedOne);
  pu = j * kFixedOne + static_cast<std::int64_t>(floor(((a + unit_interval(h)) / p.k - 0.5) * one));
  pv = k * kFixedOne + static_cast<std::int64_t>(floor(((b + unit_interval(splitmix_hash(h))) / p.k - 0.5) * one));
}

// What a column's pass needs besides its crossings.
struct CoverageColumnParams {
  std::int64_t nx = 0, ny = 0;
  float weight = 1.0f;  // 1 / k^2: one ray's share
  int points = 0;       // uniform sampling's points per voxel; 0: exact integration
};

// A column's crossing (ray, x), then, in the same place, one of its run
// events (x, delta).
struct ColumnEntry {
  double x;
  std::int32_t ray;
  float delta;
};

// The crossings of row k's rays with the triangle of fixed-point corners
// a, b, c: emit(j, ray, x) for each. The triangle's (column, ray) pairs are
// numbered q = (j - j0) * k^2 + ray; this call takes q = first, first +
// stride, ... so that a GPU's warp shares one triangle (the host takes
// first 0, stride 1: all of them).
template <typename Emit>
VOXD_HD inline void cross_row_triangle(const std::int64_t* a, const std::int64_t* b, const std::int64_t* c,
                                       std::int64_t k, std::int64_t ny, const CoverageRayPattern& p, int first,
                                       int stride, Emit&& emit) {
  RayTriangle t;
  std::int64_t j0, j1;
  if (!make_ray_triangle(a, b, c, t) || !row_columns(t, k, 0, ny, j0, j1)) return;
  plane(t);
  const int rays = p.k * p.k;
  const std::int64_t pairs = (j1 - j0 + 1) * rays;
  for (std::int64_t q = first; q < pairs; q += stride) {
    const std::int64_t j = j0 + q / rays;
    const int r = static_cast<int>(q % rays);
    std::int64_t pu, pv;
    coverage_ray_position(p, j, k, r / p.k, r % p.k, pu, pv);
    double x;
    if (cross_ray(t, pu, pv, x)) emit(j, r, x);
  }
}

// Sorts [begin, end) by `less` in place, one thread's work on one column:
// insertion sort for the short runs most columns have, heapsort (no
// recursion, no scratch) past them.
template <typename T, typename Less>
VOXD_HD inline void sort_column(T* v, std::int64_t n, Less less) {
  if (n <= 32) {
    for (std::int64_t i = 1; i < n; ++i) {
      const T item = v[i];
      std::int64_t j = i;
      for (; j > 0 && less(item, v[j - 1]); --j) v[j] = v[j - 1];
      v[j] = item;
    }
    return;
  }
  const auto sift = [&](std::int64_t root, std::int64_t size) {
    const T item = v[root];
    for (std::int64_t child = 2 * root + 1; child < size; child = 2 * root + 1) {
      if (child + 1 < size && less(v[child], v[child + 1])) ++child;
      if (!less(item, v[child])) break;
      v[root] = v[child];
      root = child;
    }
    v[root] = item;
  };
  for (std::int64_t i = n / 2; i-- > 0;) sift(i, n);
  for (std::int64_t size = n; size-- > 1;) {
    const T top = v[0];
    v[0] = v[size];
    v[size] = top;
    sift(0, size);
  }
}

// One column: its crossings [entries, entries + n) in any order become its
// row of nx coverages, added to `row` (zero before).
VOXD_HD inline void fill_coverage_column(ColumnEntry* entries, std::int64_t n, const CoverageColumnParams& params,
                                         float* row) {
  sort_column(entries, n, [](const ColumnEntry& l, const ColumnEntry& r) {
    return l.ray < r.ray || (l.ray == r.ray && l.x < r.x);
  });
  const std::int64_t events = pair_runs(entries, entries + n, static_cast<double>(params.nx), params.weight, entries);
  if (events == 0) return;
  sort_column(entries, events, [](const ColumnEntry& l, const ColumnEntry& r) {
    return l.x < r.x || (l.x == r.x && l.delta < r.delta);
  });
  if (params.points > 0)
    sample_runs(entries, entries + events, row, params.nx, params.points);
  else
    integrate_runs(entries, entries + events, row, params.nx);
  clamp_coverage(row, params.nx);
}

}  // namespace voxd::detail
