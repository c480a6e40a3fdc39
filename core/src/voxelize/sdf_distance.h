#pragma once
// The exact point-triangle distance of the signed distance field, written
// once for the CPU (sdf_triangle.h: glm::dvec3) and the CUDA kernels
// (sdf_band_kernels.h: a plain vector of three doubles), so both compute the
// same bits: every vector operation is spelled out component by component in
// glm's order (dot: (x + y) + z; cross as glm writes it), the fused
// multiply-adds are explicit (fma is exact on both sides) and nothing is
// contracted (the CPU build has no FMA, the kernels build with -fmad=false).
// Why the regions are found this way: sdf_triangle.h.
#include <float.h>
#include <math.h>

#include "voxelize/host_device.h"

namespace voxd::sdf {

template <class V>
VOXD_HD inline V vsub(const V& a, const V& b) {
  return V(a.x - b.x, a.y - b.y, a.z - b.z);
}
template <class V>
VOXD_HD inline V vscale(double t, const V& v) {
  return V(t * v.x, t * v.y, t * v.z);
}
template <class V>
VOXD_HD inline double vdot(const V& a, const V& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
template <class V>
VOXD_HD inline V vcross(const V& a, const V& b) {
  return V(a.y * b.z - b.y * a.z, a.z * b.x - b.z * a.x, a.x * b.y - b.x * a.y);
}

// a*b - c*d with a single rounding (Kahan's algorithm with FMA).
VOXD_HD inline double diff_of_products(double a, double b, double c, double d) {
  const double w = c * d;
  const double e = fma(-c, d, w);
  const double f = fma(a, b, -w);
  return f + e;
}

// A triangle with what every distance evaluation needs precomputed (see
// sdf_triangle.h for why these quantities).
template <class V>
struct TriangleOf {
  V a, b, c;
  V ab, bc, ca;             // edges
  V n;                      // ab x (c - a)
  V in_ab, in_bc, in_ca;    // n x edge: in-plane normals of the edges, pointing into the triangle
  double nn = 0.0;          // |n|^2
  bool degenerate = true;   // no area: a segment or a point, measured to its edges

  TriangleOf() = default;
  VOXD_HD TriangleOf(const V& a_, const V& b_, const V& c_)
      : a(a_), b(b_), c(c_), ab(vsub(b_, a_)), bc(vsub(c_, b_)), ca(vsub(a_, c_)) {
    const V ac = vsub(c, a);
    n = vcross(ab, ac);
    nn = vdot(n, n);
    // A thin triangle's cross product cancels almost entirely; the plain
    // products would leave the normal's direction off by eps |ab||ac| / |n|.
    if (nn < 1e-6 * vdot(ab, ab) * vdot(ac, ac)) {
      n = V(diff_of_products(ab.y, ac.z, ab.z, ac.y), diff_of_products(ab.z, ac.x, ab.x, ac.z),
            diff_of_products(ab.x, ac.y, ab.y, ac.x));
      nn = vdot(n, n);
    }
    // Subnormal, zero, infinite or NaN: no usable plane (a tiny or flat
    // triangle), and its edges are then within a rounding error of every
    // point of it.
    degenerate = !(nn >= DBL_MIN) || !(nn <= DBL_MAX);
    in_ab = vcross(n, ab);
    in_bc = vcross(n, bc);
    in_ca = vcross(n, ca);
  }
};

// Squared distance from a point to the segment [v, v + e], given p - v.
template <class V>
VOXD_HD inline double segment_distance2(const V& vp, const V& e) {
  const double ee = vdot(e, e);
  double t = 0.0;
  if (ee > 0.0) {
    t = vdot(vp, e) / ee;
    t = t < 0.0 ? 0.0 : 1.0 < t ? 1.0 : t;
  }
  const V d = vsub(vp, vscale(t, e));
  return vdot(d, d);
}

VOXD_HD inline double min_of(double a, double b) { return b < a ? b : a; }

template <class V>
VOXD_HD inline double distance2(const TriangleOf<V>& t, const V& p) {
  const V ap = vsub(p, t.a), bp = vsub(p, t.b), cp = vsub(p, t.c);
  if (t.degenerate)
    return min_of(min_of(segment_distance2(ap, t.ab), segment_distance2(bp, t.bc)), segment_distance2(cp, t.ca));
  const double s_ab = vdot(t.in_ab, ap), s_bc = vdot(t.in_bc, bp), s_ca = vdot(t.in_ca, cp);
  if (s_ab >= 0.0 && s_bc >= 0.0 && s_ca >= 0.0) {
    const double h = vdot(t.n, ap);
    return h * h / t.nn;
  }
  double best = HUGE_VAL;
  if (s_ab < 0.0) best = segment_distance2(ap, t.ab);
  if (s_bc < 0.0) best = min_of(best, segment_distance2(bp, t.bc));
  if (s_ca < 0.0) best = min_of(best, segment_distance2(cp, t.ca));
  return best;
}

}  // namespace voxd::sdf
