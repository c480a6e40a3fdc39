#pragma once
// Generalized winding number of a triangle soup (Jacobson, Kavan and
// Sorkine-Hornung 2013): w(p) = (1/4pi) * sum of the signed solid angles the
// triangles subtend at p. It is 1 inside and 0 outside a closed, outward
// oriented surface, counts nested or overlapping shells (2 inside two shells),
// and degrades gracefully for open surfaces, where it is a smooth harmonic
// function away from the triangles instead of a broken parity.
//
// WindingNumberField evaluates it fast with the hierarchy of Barill, Dickson,
// Schmidt, Levin and Jacobson 2018 ("Fast winding numbers for soups and
// clouds"): a BVH over the triangles, per node a far-field Taylor expansion of
// the solid-angle kernel (dipole, first- and second-order terms: their
// "order 3"), used for nodes that are more than `beta` node radii away; nearer
// nodes are summed exactly.
#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "voxd/mesh.h"

namespace voxd {

class JobControl;

class WindingNumberField {
 public:
  // Barill et al.'s accuracy parameter: a node's expansion is used when the
  // query is farther than beta times the node radius from its expansion
  // centre. With beta = 2 the error is typically ~1e-3 and at worst a few
  // 1e-2 where many shells are nested concentrically (their truncation errors
  // add up); the tests measure it. The cost grows roughly as beta^2.
  static constexpr double kDefaultBeta = 2.0;

  // Builds the hierarchy once (O(n log n)). The mesh may be a soup: no
  // welding, degenerate triangles allowed. The field keeps its own copy of the
  // geometry; `mesh` need not outlive it. With a `control`, construction
  // throws Error(cancelled) soon after cancellation is requested (within tens
  // of milliseconds for millions of triangles).
  explicit WindingNumberField(const Mesh& mesh, double beta = kDefaultBeta, const JobControl* control = nullptr);

  // Fast winding number at p. Finite everywhere; on a face it is the mean of
  // the values on either side (1/2 on a closed mesh).
  double operator()(glm::dvec3 p) const;

  // True if some triangle comes within `radius` of `center` (closed ball).
  bool surface_within(glm::dvec3 center, double radius) const;

  // An upper bound on |w(x) - w(center)| over the ball of `radius` around
  // `center`, valid when that ball holds no triangle (see surface_within).
  // It comes from the boundary curve of the surface only (the edges whose
  // opposite twins are missing), so it is 0 for a closed surface, where w is
  // constant off the surface. Stops as soon as the bound exceeds `limit` and
  // then returns some value > limit.
  double variation_bound(glm::dvec3 center, double radius, double limit) const;

  // True when every edge is cancelled by an opposite twin (a closed,
  // consistently oriented surface, possibly several shells).
  bool closed() const { return nodes_.empty() || nodes_.front().boundary_length == 0.0; }
  std::size_t triangle_count() const { return triangles_.size(); }

 private:
  struct Triangle {
    // Kept as the mesh's floats (exactly), widened to double when used: half
    // the memory, which dominates for meshes of millions of triangles.
    glm::vec3 a, b, c;
    // How many times each edge (a->b, b->c, c->a) counts in the boundary
    // curve of the soup: 0 when cancelled by opposite twins.
    std::uint32_t boundary_multiplicity[3];
  };
  // Fields read by every evaluation come first, so a visit touches few cache lines.
  struct Node {
    glm::dvec3 center{0.0};  // area-weighted centroid: the expansion point
    double radius = 0.0;     // every vertex of the node is within radius of center
    glm::dvec3 dipole{0.0};  // sum of area * unit normal
    // Symmetric part of sum(area * normal (x) (centroid - center)): the
    // first-order term of the expansion, as xx, yy, zz, xy, xz, yz.
    double first_order[6] = {};
    // Second-order term: for each normal component i, the symmetric matrix
    // sum(area * normal_i * second moment of (x - center) over the triangle),
    // as xx, yy, zz, xy, xz, yz; and its contraction with the identity that
    // the kernel needs (see operator()).
    double second_order[3][6] = {};
    glm::dvec3 second_order_traces{0.0};
    std::uint32_t begin = 0, end = 0;  // triangle range in triangles_
    std::uint32_t right = 0;           // right child; the left child is this + 1; 0 for a leaf
    glm::dvec3 box_min{0.0}, box_max{0.0};
    double boundary_length = 0.0;  // total length (with multiplicity) of boundary edges
    bool leaf() const { return right == 0; }
  };

  std::uint32_t build(std::vector<std::uint32_t>& order, std::uint32_t begin, std::uint32_t end,
                      const std::vector<glm::dvec3>& centroids, const JobControl* control);
  void compute_expansions(const JobControl* control);

  double beta_;
  std::vector<Triangle> triangles_;  // in BVH leaf order
  std::vector<Node> nodes_;          // depth-first; nodes_[0] is the root
};

// Brute-force winding number: the sum over all triangles of their solid angle
// (Van Oosterom and Strackee 1983) over 4pi. O(n) per point; for tests and as
// the reference of the fast field. Finite everywhere; on a face, the mean of
// the two sides.
double winding_number_exact(const Mesh& mesh, glm::dvec3 p);

}  // namespace voxd
