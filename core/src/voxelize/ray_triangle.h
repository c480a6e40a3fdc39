#pragma once
// One triangle against rays along x at fixed-point places (u = y, v = z):
// whether a ray crosses it, and where. Written once for the CPU (row_rays.h:
// coverage and palette rays) and the CUDA kernels (core/src/cuda/
// coverage_kernel.cu), so both find the same crossings at the same x bits.
//
// Exactness: integer edge functions in __int128, ties broken by simulation
// of simplicity as in the parity scan converter, so a ray through a shared
// edge or vertex of a closed mesh crosses it exactly once. The crossing's x
// comes from the triangle's plane in double, with only correctly rounded
// operations and no fused multiply-add on either side (the kernels build with
// -fmad=false); the one conversion a library might round its own way,
// __int128 to double, is spelled out (int128_to_double.h).
#include <cstdint>

#include "voxelize/fixed_point.h"
#include "voxelize/host_device.h"
#include "voxelize/int128_to_double.h"

namespace voxd::detail {

// Sign of an edge function after displacing the point by (eps, eps^2) in
// (u, v): never zero for a non-degenerate edge (simulation of simplicity).
VOXD_HD inline int displaced_sign(__int128 e, std::int64_t du, std::int64_t dv) {
  if (e != 0) return e > 0 ? 1 : -1;
  if (dv != 0) return dv > 0 ? -1 : 1;
  return du > 0 ? 1 : -1;
}

// A triangle as rays along x see it: its corners' (u, v), their box, the
// orientation, and (once plane() is called) x as a function of (u, v).
struct RayTriangle {
  __int128 det;          // twice the projected area
  std::int64_t p[3][2];  // (u, v) of the corners
  std::int64_t x[3];     // x of the corners
  std::int64_t minu, maxu, minv, maxv;
  int sigma;             // the sign of det
  double gu, gv;         // x(u, v) = x[0] + gu (u - p[0][0]) + gv (v - p[0][1])
};

// The triangle of fixed-point corners a, b, c ({x, y, z} each); false when it
// is edge-on to the rays (no ray crosses it).
VOXD_HD inline bool make_ray_triangle(const std::int64_t* a, const std::int64_t* b, const std::int64_t* c,
                                      RayTriangle& t) {
  const std::int64_t au = a[1], av = a[2], bu = b[1], bv = b[2], cu = c[1], cv = c[2];
  const __int128 det = static_cast<__int128>(bu - au) * (cv - av) - static_cast<__int128>(bv - av) * (cu - au);
  if (det == 0) return false;
  t.det = det;
  t.p[0][0] = au, t.p[0][1] = av, t.p[1][0] = bu, t.p[1][1] = bv, t.p[2][0] = cu, t.p[2][1] = cv;
  t.x[0] = a[0], t.x[1] = b[0], t.x[2] = c[0];
  t.sigma = det > 0 ? 1 : -1;
  t.minu = au < bu ? (au < cu ? au : cu) : (bu < cu ? bu : cu);
  t.maxu = au > bu ? (au > cu ? au : cu) : (bu > cu ? bu : cu);
  t.minv = av < bv ? (av < cv ? av : cv) : (bv < cv ? bv : cv);
  t.maxv = av > bv ? (av > cv ? av : cv) : (bv > cv ? bv : cv);
  t.gu = t.gv = 0.0;  // plane(): most triangles binned to a row miss it
  return true;
}

// Sets x(u, v), as in the parity scan converter (voxelize/column_scan.h):
// call once the triangle is known to meet a row.
VOXD_HD inline void plane(RayTriangle& t) {
  const double e1x = static_cast<double>(t.x[1] - t.x[0]), e2x = static_cast<double>(t.x[2] - t.x[0]);
  const double e1u = static_cast<double>(t.p[1][0] - t.p[0][0]), e1v = static_cast<double>(t.p[1][1] - t.p[0][1]);
  const double e2u = static_cast<double>(t.p[2][0] - t.p[0][0]), e2v = static_cast<double>(t.p[2][1] - t.p[0][1]);
  const double nx = int128_to_double(t.det);
  t.gu = -(e1v * e2x - e1x * e2v) / nx;
  t.gv = -(e1x * e2u - e1u * e2x) / nx;
}

// The columns [j0, j1] within [j_begin, j_end) of row k whose rays (within
// half a voxel of the column's centre line) can reach the triangle; false
// when there are none.
VOXD_HD inline bool row_columns(const RayTriangle& t, std::int64_t k, std::int64_t j_begin, std::int64_t j_end,
                                std::int64_t& j0, std::int64_t& j1) {
  const std::int64_t half = kFixedOne / 2;
  if (t.maxv < k * kFixedOne - half || t.minv >= k * kFixedOne + half) return false;
  const std::int64_t lo = floor_fixed(t.minu + half), hi = floor_fixed(t.maxu + half);
  j0 = j_begin > lo ? j_begin : lo;
  j1 = j_end - 1 < hi ? j_end - 1 : hi;
  return j0 <= j1;
}

// Whether the ray at (pu, pv) crosses the triangle (plane() set), and where:
// x in voxel units, voxel i spanning [i, i + 1) along the ray.
VOXD_HD inline bool cross_ray(const RayTriangle& t, std::int64_t pu, std::int64_t pv, double& x) {
  if (pu < t.minu || pu > t.maxu || pv < t.minv || pv > t.maxv) return false;
  for (int e = 0; e < 3; ++e) {
    const int n = e == 2 ? 0 : e + 1;
    const std::int64_t du = t.p[n][0] - t.p[e][0], dv = t.p[n][1] - t.p[e][1];
    const __int128 f = static_cast<__int128>(du) * (pv - t.p[e][1]) - static_cast<__int128>(dv) * (pu - t.p[e][0]);
    if (t.sigma * displaced_sign(f, du, dv) <= 0) return false;
  }
  const double q = static_cast<double>(t.x[0]) + t.gu * static_cast<double>(pu - t.p[0][0]) +
                   t.gv * static_cast<double>(pv - t.p[0][1]);
  x = q / static_cast<double>(kFixedOne) + 0.5;
  return true;
}

}  // namespace voxd::detail
