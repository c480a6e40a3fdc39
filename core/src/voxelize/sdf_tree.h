#pragma once
// Exact nearest-triangle queries for the signed distance field beyond its
// band: a bounding volume hierarchy of oriented boxes (see below).
#include <array>
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "analysis/progress_span.h"
#include "voxd/mesh.h"
#include "voxelize/sdf_triangle.h"

namespace voxd::sdf {


// Bounding volume hierarchy over the triangles, median splits of centroids
// along the longest axis, four triangles per leaf. Each node is bounded by a
// box oriented along the mean normal of its triangles (and in that plane
// along their principal axis), thin for a smooth patch. Seen from afar, a
// smooth surface's triangles are all nearly as close as the nearest one:
// axis-aligned boxes along a tilted patch stick out towards the query, and on
// the benchmark torus at 128^3 about 240 leaves per query have an
// axis-aligned box nearer than the answer, against 10 with oriented boxes
// (whose bound grows
// with the offset along the surface, so only the nodes near the foot point
// stay open); adding the axis-aligned box as a second bound gained nothing.
class TriangleTree {
 public:
  static constexpr std::uint32_t kNone = ~std::uint32_t{0};
  struct Hit {
    double d2 = kInfinity;
    std::uint32_t triangle = kNone;  // index in leaf order; kNone: nothing below the bound
  };

  TriangleTree(const Mesh& mesh, int threads, const detail::ProgressSpan& progress);

  // The nearest triangle among those closer than sqrt(bound2), starting from
  // the candidate `hint` (kNone for none).
  Hit nearest(const dvec3& p, double bound2, std::uint32_t hint) const;

 private:
  static constexpr std::uint32_t kLeafSize = 4;
  struct Node {           // an oriented box:
    glm::vec3 centre;
    glm::vec3 axis, axis2;  // in the plane of the triangles, and
    glm::vec3 normal;       // their mean normal; orthonormal up to float rounding
    glm::vec3 half;         // half-extents along the three, rounded up
    std::uint32_t right;  // inner node: index of the right child (the left one follows the node)
    std::uint32_t count;  // leaf: triangles [right, right + count); 0 for inner nodes
  };
  using Corners = std::array<glm::vec3, 3>;

  static std::uint32_t node_count(std::uint32_t triangles) {
    return triangles <= kLeafSize ? 1 : 1 + node_count(triangles / 2) + node_count(triangles - triangles / 2);
  }
  void make_node(std::uint32_t index, std::uint32_t begin, std::uint32_t end);
  // Splits order_[begin, end) at its middle by centroid; returns the middle.
  std::uint32_t split(std::uint32_t begin, std::uint32_t end);
  std::uint32_t build(std::uint32_t index, std::uint32_t begin, std::uint32_t end);
  // A lower bound of the squared distance from p to the node's triangles.
  static double lower_bound2(const Node& node, const dvec3& p);
  double triangle_distance2(std::uint32_t t, const dvec3& p) const {
    const Corners& c = corners_[t];
    return distance2(Triangle(dvec3(c[0]), dvec3(c[1]), dvec3(c[2])), p);
  }

  std::vector<Corners> corners_;  // in leaf order once built
  // While building: triangle indices, split in place, and their centroids.
  std::vector<std::uint32_t> order_;
  std::vector<glm::vec3> centroids_;
  std::vector<Node> nodes_;
};

// Rounds up to a float, with a relative margin that absorbs the rounding of

}  // namespace voxd::sdf
