#pragma once
// Exact scan conversion of one triangle onto a grid of ray columns.
//
// Rays run along axis `ray`; a column is identified by its integer indices
// (ju, kv) on the two other axes, with its centre line at fixed-point
// coordinates (ju * kFixedOne, kv * kFixedOne). For every column whose centre
// line crosses the triangle, emit(ju, kv, c) is called with c the index of the
// first voxel centre strictly beyond the crossing (crossing x, c = floor(x)+1).
//
// Watertightness: the inside-triangle test uses exact integer edge functions
// and breaks ties by simulation of simplicity, treating each column centre as
// if displaced by (eps, eps^2) in (u, v). No displaced centre can lie on an
// edge or vertex, so a column through a shared edge or vertex of a closed
// surface crosses it exactly once per sheet: no double counts, no gaps, also
// for axis-aligned faces lying exactly on voxel-centre planes (those are
// edge-on to the rays and contribute no crossing at all).
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "voxelize/fixed_point_mesh.h"
#include "voxelize/int128_to_double.h"

namespace voxd::detail {

using i128 = __int128;

// Smallest integer j in [lo - 1, hi + 1] with j * m >= c (m > 0), where an
// answer below lo - 1 is reported as lo - 1 and one above hi as hi + 1. A
// double estimate is corrected with exact integer checks (usually 0 steps).
inline std::int64_t ceil_div_clamped(i128 c, i128 m, std::int64_t lo, std::int64_t hi) {
  const double t = int128_to_double(c) / int128_to_double(m);
  std::int64_t j;
  if (!(t > static_cast<double>(lo - 1))) {
    j = lo - 1;
  } else if (!(t < static_cast<double>(hi + 1))) {
    j = hi + 1;
  } else {
    j = static_cast<std::int64_t>(std::ceil(t));
  }
  while (j > lo - 1 && static_cast<i128>(j - 1) * m >= c) --j;
  while (j <= hi && static_cast<i128>(j) * m < c) ++j;
  return j;
}

struct ScanAxes {
  int ray;  // axis the rays run along
  int u;    // column index axis iterated inside a row
  int v;    // row axis (the axis work is partitioned along)
};

template <typename Emit>
inline void scan_triangle(const FixedPoint& A, const FixedPoint& B, const FixedPoint& C, const ScanAxes& axes,
                          std::int64_t row_begin, std::int64_t row_end, std::int64_t columns_u, Emit&& emit) {
  const std::int64_t au = A[axes.u], av = A[axes.v], bu = B[axes.u], bv = B[axes.v], cu = C[axes.u], cv = C[axes.v];
  // Most triangles of a fine mesh cover no column centre at all: the box
  // tests come first, before anything costs.
  const std::int64_t k0 = std::max(row_begin, ceil_fixed(std::min({av, bv, cv})));
  const std::int64_t k1 = std::min(row_end - 1, floor_fixed(std::max({av, bv, cv})));
  if (k0 > k1) return;
  const std::int64_t jbox0 = std::max<std::int64_t>(0, ceil_fixed(std::min({au, bu, cu})));
  const std::int64_t jbox1 = std::min<std::int64_t>(columns_u - 1, floor_fixed(std::max({au, bu, cu})));
  if (jbox0 > jbox1) return;
  const i128 det = static_cast<i128>(bu - au) * (cv - av) - static_cast<i128>(bv - av) * (cu - au);
  if (det == 0) return;  // edge-on to the rays: the displaced centres never hit it
  const int sigma = det > 0 ? 1 : -1;

  // Plane of the triangle: x(u, v) = ax + gu * (u - au) + gv * (v - av),
  // from the normal (nx, nu, nv) in (ray, u, v) coordinates; nx == det.
  const double ax = static_cast<double>(A[axes.ray]);
  const double e1x = static_cast<double>(B[axes.ray] - A[axes.ray]), e1u = static_cast<double>(bu - au),
               e1v = static_cast<double>(bv - av);
  const double e2x = static_cast<double>(C[axes.ray] - A[axes.ray]), e2u = static_cast<double>(cu - au),
               e2v = static_cast<double>(cv - av);
  const double nx = int128_to_double(det);
  const double gu = -(e1v * e2x - e1x * e2v) / nx;  // dx/du
  const double gv = -(e1x * e2u - e1u * e2x) / nx;  // dx/dv
  constexpr double kInvOne = 1.0 / static_cast<double>(kFixedOne);
  const bool flat = gu == 0.0 && gv == 0.0;
  auto crossing_index = [&](std::int64_t j, std::int64_t k) {
    const double x = flat ? ax
                          : ax + gu * (static_cast<double>(j * kFixedOne) - static_cast<double>(au)) +
                                gv * (static_cast<double>(k * kFixedOne) - static_cast<double>(av));
    return static_cast<std::int64_t>(std::floor(x * kInvOne)) + 1;
  };

  // Fast path for the common small triangle: test every column of the
  // bounding box with incrementally updated edge functions. Exact in int64:
  // edge extents and offsets within the box stay below 2^30 fixed units, so
  // products stay below 2^61.
  constexpr std::int64_t kSmallSpan = std::int64_t{1} << 30;
  const std::int64_t cols = jbox1 - jbox0 + 1, rows = k1 - k0 + 1;
  if (cols * rows <= 64 && std::max({au, bu, cu}) - std::min({au, bu, cu}) < kSmallSpan &&
      std::max({av, bv, cv}) - std::min({av, bv, cv}) < kSmallSpan) {
    const FixedPoint* tri[3] = {&A, &B, &C};
    std::int64_t f[3], step_j[3], step_k[3];
    for (int e = 0; e < 3; ++e) {
      const std::int64_t pu = (*tri[e])[axes.u], pv = (*tri[e])[axes.v];
      const std::int64_t du = (*tri[(e + 1) % 3])[axes.u] - pu, dv = (*tri[(e + 1) % 3])[axes.v] - pv;
      // E = du*(v - pv) - dv*(u - pu), flipped by sigma so "inside" is E > 0.
      // On a tie (E == 0) the displaced centre is inside iff
      // sigma * (dv != 0 ? -dv : du) > 0: folded in as a +1 bias.
      const std::int64_t tie = dv != 0 ? -dv : du;
      const std::int64_t e0 = du * (k0 * kFixedOne - pv) - dv * (jbox0 * kFixedOne - pu);
      f[e] = sigma * e0 + ((sigma > 0) == (tie > 0) ? 1 : 0);
      step_j[e] = -sigma * dv * kFixedOne;
      step_k[e] = sigma * du * kFixedOne;
    }
    for (std::int64_t k = k0; k <= k1; ++k) {
      std::int64_t g0 = f[0], g1 = f[1], g2 = f[2];
      for (std::int64_t j = jbox0; j <= jbox1; ++j) {
        if (((g0 - 1) | (g1 - 1) | (g2 - 1)) >= 0) emit(j, k, crossing_index(j, k));
        g0 += step_j[0];
        g1 += step_j[1];
        g2 += step_j[2];
      }
      f[0] += step_k[0];
      f[1] += step_k[1];
      f[2] += step_k[2];
    }
    return;
  }

  // Edge functions E(p) = du * (pv - pv0) - dv * (pu - pu0) for edges a->b,
  // b->c, c->a. Along a row pv = k*S: E(j) = (du*S*k + base) - dv*S*j.
  struct Edge {
    std::int64_t du, dv;
    i128 base;
  };
  const Edge edges[3] = {
      {bu - au, bv - av, static_cast<i128>(bv - av) * au - static_cast<i128>(bu - au) * av},
      {cu - bu, cv - bv, static_cast<i128>(cv - bv) * bu - static_cast<i128>(cu - bu) * bv},
      {au - cu, av - cv, static_cast<i128>(av - cv) * cu - static_cast<i128>(au - cu) * cv},
  };

  for (std::int64_t k = k0; k <= k1; ++k) {
    std::int64_t jlo = jbox0, jhi = jbox1;
    const i128 kS = static_cast<i128>(k) * kFixedOne;
    for (const Edge& e : edges) {
      const i128 c = static_cast<i128>(e.du) * kS + e.base;  // E(j) = c - dv*S*j
      if (e.dv == 0) {
        // Constant along the row; on a tie the displaced centre decides by du.
        const bool inside = c != 0 ? ((c > 0) == (sigma > 0)) : ((e.du > 0) == (sigma > 0));
        if (!inside) {
          jlo = 1;
          jhi = 0;
          break;
        }
        continue;
      }
      const i128 m = static_cast<i128>(e.dv) * kFixedOne;
      if ((sigma > 0) == (e.dv > 0)) {
        // Inside for j < c/m strictly (a tie falls outside this edge).
        const std::int64_t first_out = (m > 0) ? ceil_div_clamped(c, m, jlo, jhi) : ceil_div_clamped(-c, -m, jlo, jhi);
        jhi = std::min(jhi, first_out - 1);
      } else {
        // Inside for j >= c/m (a tie falls inside this edge).
        const std::int64_t first_in = (m > 0) ? ceil_div_clamped(c, m, jlo, jhi) : ceil_div_clamped(-c, -m, jlo, jhi);
        jlo = std::max(jlo, first_in);
      }
      if (jlo > jhi) break;
    }
    if (jlo > jhi) continue;
    for (std::int64_t j = jlo; j <= jhi; ++j) emit(j, k, crossing_index(j, k));
  }
}

}  // namespace voxd::detail
