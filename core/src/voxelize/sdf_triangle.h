#pragma once
// The exact point-triangle distance of the signed distance field, shared by
// the band scatter and the nearest-triangle queries so both give the same
// bits (see voxd/voxelize/sdf.h on precision).
#include <algorithm>
#include <cfloat>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

namespace voxd::sdf {

using glm::dvec3;

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// a*b - c*d with a single rounding (Kahan's algorithm with FMA).
inline double diff_of_products(double a, double b, double c, double d) {
  const double w = c * d;
  const double e = std::fma(-c, d, w);
  const double f = std::fma(a, b, -w);
  return f + e;
}

// A triangle with what every distance evaluation needs precomputed.
//
// Why not Ericson's optimized region tests as printed (the d1..d6 dot
// products and va = d3*d6 - d5*d4 ...): those differences of products cancel
// with an error of about eps |p - a|^2 |edge|^2, against a true value of
// |n|^2 times a barycentric coordinate, so on thin triangles the regions
// shift by about eps L^3 / h^2 (L: edge length, h: height), and with two
// coincident vertices the edge case divides 0 by 0. Run on the tests'
// slivers, the printed version returns NaN and errors up to 1e-3 relative.
// Here the same Voronoi regions are found from the signed in-plane distances
// to the edge lines, (n x edge) . (p - vertex), whose error is eps |p -
// vertex|, with an accurately computed normal: a point inside all three is
// in the face region (distance to the plane); otherwise the closest point
// lies on an edge whose line p is outside of (if it is a vertex, on one of
// the two edges meeting there), so the minimum over those segments is exact.
struct Triangle {
  dvec3 a, b, c;
  dvec3 ab, bc, ca;        // edges
  dvec3 n;                 // ab x (c - a)
  dvec3 in_ab, in_bc, in_ca;  // n x edge: in-plane normals of the edges, pointing into the triangle
  double nn = 0.0;         // |n|^2
  bool degenerate = true;  // no area: a segment or a point, measured to its edges

  Triangle(const dvec3& a_, const dvec3& b_, const dvec3& c_) : a(a_), b(b_), c(c_), ab(b_ - a_), bc(c_ - b_), ca(a_ - c_) {
    const dvec3 ac = c - a;
    n = glm::cross(ab, ac);
    nn = glm::dot(n, n);
    // A thin triangle's cross product cancels almost entirely; the plain
    // products would leave the normal's direction off by eps |ab||ac| / |n|.
    if (nn < 1e-6 * glm::dot(ab, ab) * glm::dot(ac, ac)) {
      n = {diff_of_products(ab.y, ac.z, ab.z, ac.y), diff_of_products(ab.z, ac.x, ab.x, ac.z),
           diff_of_products(ab.x, ac.y, ab.y, ac.x)};
      nn = glm::dot(n, n);
    }
    // Subnormal or zero: no usable plane (a tiny or flat triangle), and its
    // edges are then within a rounding error of every point of it.
    degenerate = !(nn >= DBL_MIN) || !std::isfinite(nn);
    in_ab = glm::cross(n, ab);
    in_bc = glm::cross(n, bc);
    in_ca = glm::cross(n, ca);
  }
};

// Squared distance from a point to the segment [v, v + e], given p - v.
inline double segment_distance2(const dvec3& vp, const dvec3& e) {
  const double ee = glm::dot(e, e);
  const double t = ee > 0.0 ? std::clamp(glm::dot(vp, e) / ee, 0.0, 1.0) : 0.0;
  const dvec3 d = vp - t * e;
  return glm::dot(d, d);
}

inline double distance2(const Triangle& t, const dvec3& p) {
  const dvec3 ap = p - t.a, bp = p - t.b, cp = p - t.c;
  if (t.degenerate)
    return std::min({segment_distance2(ap, t.ab), segment_distance2(bp, t.bc), segment_distance2(cp, t.ca)});
  const double s_ab = glm::dot(t.in_ab, ap), s_bc = glm::dot(t.in_bc, bp), s_ca = glm::dot(t.in_ca, cp);
  if (s_ab >= 0.0 && s_bc >= 0.0 && s_ca >= 0.0) {
    const double h = glm::dot(t.n, ap);
    return h * h / t.nn;
  }
  double best = kInfinity;
  if (s_ab < 0.0) best = segment_distance2(ap, t.ab);
  if (s_bc < 0.0) best = std::min(best, segment_distance2(bp, t.bc));
  if (s_ca < 0.0) best = std::min(best, segment_distance2(cp, t.ca));
  return best;
}

}  // namespace voxd::sdf
