#pragma once
// The exact point-triangle distance of the signed distance field, shared by
// the band scatter and the nearest-triangle queries so both give the same
// bits (see voxd/voxelize/sdf.h on precision). The arithmetic itself is
// sdf_distance.h, which the CUDA kernels compile too.
#include <algorithm>
#include <cfloat>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "voxelize/sdf_distance.h"

namespace voxd::sdf {

using glm::dvec3;

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// A triangle with what every distance evaluation needs precomputed
// (sdf_distance.h).
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
using Triangle = TriangleOf<dvec3>;

}  // namespace voxd::sdf
