// Signed distance field: the narrow band by scattering triangles to voxels
// (Jones 1996), exact nearest-triangle queries for the rest of the grid when
// asked, the sign from the solid voxelization. See voxd/sdf.h.
#include "voxd/sdf.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cfloat>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <limits>
#include <mutex>
#include <thread>
#include <vector>

#include <glm/geometric.hpp>

#include "analysis/progress_span.h"
#include "voxd/error.h"
#include "voxd/parallel.h"

namespace voxd {
namespace {

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

inline dvec3 corner(const Mesh& mesh, std::size_t tri, int c) { return dvec3(mesh.corner(tri, c)); }

// The same arithmetic as Grid::center, so values match a brute force over
// grid.center() bit for bit.
inline double centre_coordinate(const Grid& g, int axis, std::int64_t i) {
  return g.origin[axis] + (static_cast<double>(i) + 0.5) * g.voxel_size;
}

// Coordinates in voxel units with voxel i's centre at i, for working out
// which voxels to visit (the distances themselves are computed in model
// units). `first` and `last` give the indices within [x, y] widened by a
// millionth of a voxel (rounding here is under 1e-11 voxel near a grid of
// the sizes allowed), clamped to [0, n - 1]; first > last when empty.
struct IndexSpace {
  dvec3 origin;
  double inv_voxel;

  explicit IndexSpace(const Grid& g) : origin(g.origin), inv_voxel(1.0 / g.voxel_size) {}
  dvec3 operator()(const dvec3& p) const { return (p - origin) * inv_voxel - 0.5; }
  static std::int64_t first(double x, std::int64_t n) {
    return static_cast<std::int64_t>(std::clamp(std::ceil(x - 1e-6), 0.0, static_cast<double>(n)));
  }
  static std::int64_t last(double x, std::int64_t n) {
    return static_cast<std::int64_t>(std::clamp(std::floor(x + 1e-6), -1.0, static_cast<double>(n) - 1.0));
  }
};

// ---------------------------------------------------------------------------
// Narrow band.

struct BandSetup {
  double band = 0.0;       // model units
  double to_model = 1.0;   // output unit -> model units
  double to_output = 1.0;  // model units -> output unit
};

// Lowers each voxel of slabs [z0, z1) within the band of triangle t to its
// distance if that is smaller. `values` hold float(distance * to_output);
// the minimum of rounded values is the rounded minimum, so the order in which
// triangles arrive does not matter.
//
// Which voxels to visit is worked out per row in index space (voxel i's
// centre at coordinate i), cheap and with a margin for rounding: the band of
// the bounding box, of the bounding sphere and of the plane. Each visited
// voxel then gets two lower bounds in model units, relative to the triangle
// (so small numbers, small rounding): its distance to the plane and to the
// bounding sphere. If either reaches its current value the triangle cannot
// lower it; only then is the exact distance computed. Once the nearer
// triangles have been by, the sphere skips most voxels (the plane alone does
// not: along a curved surface the neighbours' planes pass close to a voxel).
void scatter_triangle(const Triangle& t, const Grid& g, const BandSetup& s, std::int64_t z0, std::int64_t z1,
                      DenseVolume<float>& values) {
  const IndexSpace index_of(g);
  const double band = s.band * index_of.inv_voxel, band2 = band * band;  // voxels
  const dvec3 lo = index_of(glm::min(glm::min(t.a, t.b), t.c)), hi = index_of(glm::max(glm::max(t.a, t.b), t.c));
  const dvec3 centroid = (t.a + t.b + t.c) / 3.0;
  const double radius =
      std::sqrt(std::max({glm::dot(t.a - centroid, t.a - centroid), glm::dot(t.b - centroid, t.b - centroid),
                          glm::dot(t.c - centroid, t.c - centroid)})) * (1.0 + 1e-9);
  const dvec3 centroid_i = index_of(centroid);
  const double reach = band + radius * index_of.inv_voxel, reach2 = reach * reach;
  const dvec3 unit = t.degenerate ? dvec3(0.0) : t.n / std::sqrt(t.nn);
  const dvec3 a_i = index_of(t.a);
  // Restrict rows by the plane only where that is well conditioned.
  const double inv_unit_x = std::abs(unit.x) > 1e-3 ? 1.0 / unit.x : 0.0;

  const std::int64_t k0 = std::max(z0, IndexSpace::first(lo.z - band, g.dims.z));
  const std::int64_t k1 = std::min(z1 - 1, IndexSpace::last(hi.z + band, g.dims.z));
  const std::int64_t j0 = IndexSpace::first(lo.y - band, g.dims.y), j1 = IndexSpace::last(hi.y + band, g.dims.y);
  for (std::int64_t k = k0; k <= k1; ++k) {
    const auto kk = static_cast<double>(k);
    const double dz = std::max({lo.z - kk, kk - hi.z, 0.0}), sz = kk - centroid_i.z;
    const double cz = centre_coordinate(g, 2, k);
    float* slab = values.slab(k);
    for (std::int64_t j = j0; j <= j1; ++j) {
      const auto jj = static_cast<double>(j);
      const double dy = std::max({lo.y - jj, jj - hi.y, 0.0}), sy = jj - centroid_i.y;
      const double box_rest2 = band2 - dy * dy - dz * dz, sphere_rest2 = reach2 - sy * sy - sz * sz;
      if (box_rest2 < 0.0 || sphere_rest2 < 0.0) continue;
      const double bx = std::sqrt(box_rest2), sx = std::sqrt(sphere_rest2);
      double from = std::max(lo.x - bx, centroid_i.x - sx), to = std::min(hi.x + bx, centroid_i.x + sx);
      const double plane_yz_i = unit.y * (jj - a_i.y) + unit.z * (kk - a_i.z);
      if (inv_unit_x != 0.0) {  // |plane_yz_i + unit.x (i - a_i.x)| <= band
        const double p0 = a_i.x + (-band - plane_yz_i) * inv_unit_x, p1 = a_i.x + (band - plane_yz_i) * inv_unit_x;
        from = std::max(from, std::min(p0, p1));
        to = std::min(to, std::max(p0, p1));
      }
      const std::int64_t i0 = IndexSpace::first(from, g.dims.x), i1 = IndexSpace::last(to, g.dims.x);

      const double cy = centre_coordinate(g, 1, j);
      const double plane_yz = unit.y * (cy - t.a.y) + unit.z * (cz - t.a.z);
      const double sphere_yz2 = (cy - centroid.y) * (cy - centroid.y) + (cz - centroid.z) * (cz - centroid.z);
      float* row = slab + j * g.dims.x;
      for (std::int64_t i = i0; i <= i1; ++i) {
        const double cx = centre_coordinate(g, 0, i);
        const double limit = static_cast<double>(row[i]) * s.to_model;
        const double plane = plane_yz + unit.x * (cx - t.a.x);
        if (plane * plane >= limit * limit) continue;
        const double sphere2 = (cx - centroid.x) * (cx - centroid.x) + sphere_yz2;
        if (sphere2 >= (limit + radius) * (limit + radius)) continue;
        const double d2 = distance2(t, dvec3(cx, cy, cz));
        if (d2 >= limit * limit) continue;
        row[i] = std::min(row[i], static_cast<float>(std::sqrt(d2) * s.to_output));
      }
    }
  }
}

// Triangles grouped by the chunks of z-slabs their band reaches, so each
// thread owns a chunk of the output.
struct SlabBins {
  std::int64_t slabs_per_chunk = 1;
  std::int64_t chunk_count = 0;
  std::vector<std::uint64_t> offsets;    // chunk c: triangles[offsets[c], offsets[c + 1])
  std::vector<std::uint32_t> triangles;
};

SlabBins bin_by_slab(const Mesh& mesh, const Grid& g, double band, int threads) {
  SlabBins bins;
  const std::int64_t nz = g.dims.z;
  bins.slabs_per_chunk = std::clamp<std::int64_t>(nz / (8 * threads), 1, 16);
  bins.chunk_count = (nz + bins.slabs_per_chunk - 1) / bins.slabs_per_chunk;
  const std::size_t n = mesh.triangle_count();
  const IndexSpace index_of(g);
  const double band_voxels = band * index_of.inv_voxel;
  std::vector<std::int64_t> first(n), last(n);
  for (std::size_t t = 0; t < n; ++t) {
    // The same slabs as scatter_triangle's, by the same arithmetic.
    const dvec3 a = corner(mesh, t, 0), b = corner(mesh, t, 1), c = corner(mesh, t, 2);
    const std::int64_t k0 = IndexSpace::first(index_of(glm::min(glm::min(a, b), c)).z - band_voxels, nz);
    const std::int64_t k1 = IndexSpace::last(index_of(glm::max(glm::max(a, b), c)).z + band_voxels, nz);
    first[t] = k0 / bins.slabs_per_chunk;
    last[t] = k0 <= k1 ? k1 / bins.slabs_per_chunk : first[t] - 1;
  }
  bins.offsets.assign(static_cast<std::size_t>(bins.chunk_count) + 1, 0);
  for (std::size_t t = 0; t < n; ++t)
    for (std::int64_t c = first[t]; c <= last[t]; ++c) ++bins.offsets[static_cast<std::size_t>(c) + 1];
  for (std::size_t c = 1; c < bins.offsets.size(); ++c) bins.offsets[c] += bins.offsets[c - 1];
  bins.triangles.resize(bins.offsets.back());
  std::vector<std::uint64_t> cursor(bins.offsets.begin(), bins.offsets.end() - 1);
  for (std::size_t t = 0; t < n; ++t)
    for (std::int64_t c = first[t]; c <= last[t]; ++c)
      bins.triangles[cursor[static_cast<std::size_t>(c)]++] = static_cast<std::uint32_t>(t);
  return bins;
}

void scatter_band(const Mesh& mesh, const Grid& g, const BandSetup& s, int threads, DenseVolume<float>& values,
                  const detail::ProgressSpan& progress) {
  const SlabBins bins = bin_by_slab(mesh, g, s.band, threads);
  // Cancellation and progress every this many triangles (~1 ms of work).
  constexpr std::uint64_t kTick = 512;
  const auto total = static_cast<double>(std::max<std::uint64_t>(bins.triangles.size(), 1));
  std::atomic<std::uint64_t> done{0};
  parallel_for(0, bins.chunk_count, 1, threads, [&](std::int64_t c0, std::int64_t c1) {
    for (std::int64_t c = c0; c < c1; ++c) {
      progress.check_cancelled();
      const std::int64_t z0 = c * bins.slabs_per_chunk, z1 = std::min(g.dims.z, z0 + bins.slabs_per_chunk);
      std::uint64_t pending = 0;
      for (std::uint64_t x = bins.offsets[static_cast<std::size_t>(c)]; x < bins.offsets[static_cast<std::size_t>(c) + 1]; ++x) {
        const std::size_t t = bins.triangles[x];
        scatter_triangle(Triangle(corner(mesh, t, 0), corner(mesh, t, 1), corner(mesh, t, 2)), g, s, z0, z1, values);
        if (++pending == kTick) {
          progress.check_cancelled();
          progress.report(static_cast<double>(done.fetch_add(pending) + pending) / total);
          pending = 0;
        }
      }
      progress.report(static_cast<double>(done.fetch_add(pending) + pending) / total);
    }
  });
  progress.report(1.0);
}

// ---------------------------------------------------------------------------
// Exact nearest-triangle queries, for the voxels the band leaves clamped.

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
// the double arithmetic in lower_bound2.
inline float round_up(double v) {
  const auto f = static_cast<float>(v * (1.0 + 1e-6));
  return static_cast<double>(f) >= v ? f : std::nextafter(f, std::numeric_limits<float>::infinity());
}

void TriangleTree::make_node(std::uint32_t index, std::uint32_t begin, std::uint32_t end) {
  Node& node = nodes_[index];
  glm::vec3 lo(std::numeric_limits<float>::infinity()), hi(-std::numeric_limits<float>::infinity());
  dvec3 area(0.0);
  for (std::uint32_t x = begin; x < end; ++x) {
    const Corners& c = corners_[order_[x]];
    for (const glm::vec3& v : c) {
      lo = glm::min(lo, v);
      hi = glm::max(hi, v);
    }
    area += glm::cross(dvec3(c[1]) - dvec3(c[0]), dvec3(c[2]) - dvec3(c[0]));
  }
  // Frame: the mean normal, and in its plane the principal axis of the
  // vertices (so a patch's rectangle is tight, not a rotated patch's box).
  const double area_length = glm::length(area);
  const dvec3 n = area_length > 0.0 && std::isfinite(area_length) ? area / area_length : dvec3(0, 0, 1);
  dvec3 u(0.0);
  u[std::abs(n.x) < 0.6 ? 0 : 1] = 1.0;
  u = glm::normalize(u - glm::dot(u, n) * n);
  const dvec3 w = glm::cross(n, u), box_centre = 0.5 * (dvec3(lo) + dvec3(hi));
  double cuu = 0.0, cuw = 0.0, cww = 0.0;
  for (std::uint32_t x = begin; x < end; ++x)
    for (const glm::vec3& v : corners_[order_[x]]) {
      const double a = glm::dot(u, dvec3(v) - box_centre), b = glm::dot(w, dvec3(v) - box_centre);
      cuu += a * a;
      cuw += a * b;
      cww += b * b;
    }
  const double angle = 0.5 * std::atan2(2.0 * cuw, cuu - cww);
  node.normal = glm::vec3(n);
  node.axis = glm::vec3(std::cos(angle) * u + std::sin(angle) * w);
  // The frame as the queries will see it: float axes, the second from them.
  node.axis2 = glm::vec3(glm::cross(dvec3(node.normal), dvec3(node.axis)));
  const dvec3 f0(node.axis), f2(node.normal), f1(node.axis2);
  dvec3 lmin(kInfinity), lmax(-kInfinity);
  for (std::uint32_t x = begin; x < end; ++x)
    for (const glm::vec3& v : corners_[order_[x]]) {
      const dvec3 d = dvec3(v) - box_centre, q(glm::dot(f0, d), glm::dot(f1, d), glm::dot(f2, d));
      lmin = glm::min(lmin, q);
      lmax = glm::max(lmax, q);
    }
  const dvec3 mid = 0.5 * (lmin + lmax);
  node.centre = glm::vec3(box_centre + mid.x * f0 + mid.y * f1 + mid.z * f2);
  const dvec3 s(node.centre);
  dvec3 half(0.0);
  for (std::uint32_t x = begin; x < end; ++x)
    for (const glm::vec3& v : corners_[order_[x]]) {
      const dvec3 d = dvec3(v) - s;
      half = glm::max(half, glm::abs(dvec3(glm::dot(f0, d), glm::dot(f1, d), glm::dot(f2, d))));
    }
  // Absolute slack of a millionth of the box: rounding in lower_bound2 is
  // relative to |p - centre|, which the relative margin alone does not cover
  // when a half-extent is 0.
  const double slack = 1e-6 * glm::length(dvec3(hi) - dvec3(lo));
  node.half = {round_up(half.x + slack), round_up(half.y + slack), round_up(half.z + slack)};
}

std::uint32_t TriangleTree::split(std::uint32_t begin, std::uint32_t end) {
  glm::vec3 lo(std::numeric_limits<float>::infinity()), hi(-std::numeric_limits<float>::infinity());
  for (std::uint32_t x = begin; x < end; ++x) {
    lo = glm::min(lo, centroids_[order_[x]]);
    hi = glm::max(hi, centroids_[order_[x]]);
  }
  const glm::vec3 e = hi - lo;
  const int axis = e.x >= e.y && e.x >= e.z ? 0 : (e.y >= e.z ? 1 : 2);
  const std::uint32_t mid = begin + (end - begin) / 2;
  // Ties by index, so the tree does not depend on the library's nth_element.
  std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
                   [&](std::uint32_t x, std::uint32_t y) {
                     const float cx = centroids_[x][axis], cy = centroids_[y][axis];
                     return cx < cy || (cx == cy && x < y);
                   });
  return mid;
}

std::uint32_t TriangleTree::build(std::uint32_t index, std::uint32_t begin, std::uint32_t end) {
  make_node(index, begin, end);
  if (end - begin <= kLeafSize) {
    nodes_[index].right = begin;
    nodes_[index].count = end - begin;
    return index + 1;
  }
  const std::uint32_t mid = split(begin, end);
  const std::uint32_t right = build(index + 1, begin, mid);
  nodes_[index].right = right;
  nodes_[index].count = 0;
  return build(right, mid, end);
}

TriangleTree::TriangleTree(const Mesh& mesh, int threads, const detail::ProgressSpan& progress) {
  const std::size_t n = mesh.triangle_count();
  if (n == 0) return;
  if (n >= kNone) throw Error(ErrorCode::limit_exceeded, "too many triangles for the distance field");
  corners_.resize(n);
  centroids_.resize(n);
  order_.resize(n);
  for (std::size_t t = 0; t < n; ++t) {
    corners_[t] = {mesh.corner(t, 0), mesh.corner(t, 1), mesh.corner(t, 2)};
    centroids_[t] = (corners_[t][0] + corners_[t][1] + corners_[t][2]) / 3.0f;
    order_[t] = static_cast<std::uint32_t>(t);
  }
  const auto count = static_cast<std::uint32_t>(n);
  nodes_.resize(node_count(count));
  // The top levels one after the other, then the subtrees below them in
  // parallel: each knows its place in the node array from node_count.
  struct Task {
    std::uint32_t index, begin, end;
  };
  // Subtrees of at most 2^16 triangles (tens of milliseconds between
  // cancellation checks) and about 8 per thread, unless tiny.
  std::vector<Task> tasks{{0, 0, count}};
  const std::size_t want = static_cast<std::size_t>(std::max(threads, 1)) * 8;
  for (bool split_any = true; split_any;) {
    std::vector<Task> next;
    split_any = false;
    for (const Task& task : tasks) {
      const std::uint32_t size = task.end - task.begin;
      if (size <= (1u << 12) || (size <= (1u << 16) && tasks.size() >= want)) {
        next.push_back(task);
        continue;
      }
      progress.check_cancelled();
      make_node(task.index, task.begin, task.end);
      const std::uint32_t mid = split(task.begin, task.end);
      const std::uint32_t right = task.index + 1 + node_count(mid - task.begin);
      nodes_[task.index].right = right;
      nodes_[task.index].count = 0;
      next.push_back({task.index + 1, task.begin, mid});
      next.push_back({right, mid, task.end});
      split_any = true;
    }
    tasks.swap(next);
  }
  std::atomic<std::size_t> done{0};
  parallel_for(0, static_cast<std::int64_t>(tasks.size()), 1, threads, [&](std::int64_t t0, std::int64_t t1) {
    for (std::int64_t t = t0; t < t1; ++t) {
      progress.check_cancelled();
      const Task& task = tasks[static_cast<std::size_t>(t)];
      build(task.index, task.begin, task.end);
      progress.report(static_cast<double>(++done) / static_cast<double>(tasks.size()));
    }
  });
  std::vector<Corners> leaf_order(n);
  for (std::size_t x = 0; x < n; ++x) leaf_order[x] = corners_[order_[x]];
  corners_.swap(leaf_order);
  order_ = {};
  centroids_ = {};
}

inline double TriangleTree::lower_bound2(const Node& node, const dvec3& p) {
  // With F the frame's rows, F (x - p) = F (x - centre) - F (p - centre) and
  // |F (x - centre)| <= half per axis, so |F (x - p)| >= the clamped excess
  // below; |x - p| >= |F (x - p)| / |F|, and |F| <= 1 + 1e-6 (float axes),
  // covered by the factor.
  const dvec3 f0(node.axis), f2(node.normal), f1(node.axis2), d = p - dvec3(node.centre);
  const dvec3 excess =
      glm::max(glm::abs(dvec3(glm::dot(f0, d), glm::dot(f1, d), glm::dot(f2, d))) - dvec3(node.half), dvec3(0.0));
  return glm::dot(excess, excess) * (1.0 - 1e-5);
}

TriangleTree::Hit TriangleTree::nearest(const dvec3& p, double bound2, std::uint32_t hint) const {
  Hit best{bound2, kNone};
  if (nodes_.empty()) return best;
  if (hint != kNone) {
    const double d2 = triangle_distance2(hint, p);
    if (d2 < best.d2) best = {d2, hint};
  }
  // Depth-first, nearer child first; median splits keep the depth under 33.
  struct Entry {
    std::uint32_t node;
    double bound2;
  };
  std::array<Entry, 128> stack;
  int top = 0;
  stack[top++] = {0, lower_bound2(nodes_[0], p)};
  while (top > 0) {
    const Entry e = stack[--top];
    if (e.bound2 >= best.d2) continue;
    const Node& node = nodes_[e.node];
    if (node.count > 0) {
      for (std::uint32_t t = node.right; t < node.right + node.count; ++t) {
        const double d2 = triangle_distance2(t, p);
        if (d2 < best.d2) best = {d2, t};
      }
      continue;
    }
    Entry a{e.node + 1, lower_bound2(nodes_[e.node + 1], p)},
        b{node.right, lower_bound2(nodes_[node.right], p)};
    if (a.bound2 > b.bound2) std::swap(a, b);
    if (b.bound2 < best.d2) stack[top++] = b;
    if (a.bound2 < best.d2) stack[top++] = a;
  }
  return best;
}

void fill_beyond_band(const Mesh& mesh, const Grid& g, const BandSetup& s, float clamped, int threads,
                      DenseVolume<float>& values, const detail::ProgressSpan& progress) {
  const TriangleTree tree(mesh, threads, progress.part(0.0, 0.1));
  const detail::ProgressSpan queries = progress.part(0.1, 1.0);
  const std::int64_t nx = g.dims.x, ny = g.dims.y, rows = ny * g.dims.z;
  std::atomic<std::int64_t> done{0};
  parallel_for(0, rows, std::max<std::int64_t>(1, rows / (threads * 64)), threads, [&](std::int64_t r0, std::int64_t r1) {
    for (std::int64_t r = r0; r < r1; ++r) {
      queries.check_cancelled();
      const std::int64_t j = r % ny, k = r / ny;
      float* row = values.slab(k) + j * nx;
      const double cy = centre_coordinate(g, 1, j), cz = centre_coordinate(g, 2, k);
      // The previous voxel's distance bounds this one's (d is 1-Lipschitz),
      // and its nearest triangle is usually this one's too.
      double previous = -1.0;
      std::uint32_t hint = TriangleTree::kNone;
      for (std::int64_t i = 0; i < nx; ++i) {
        if ((i & 255) == 255) queries.check_cancelled();
        if (row[i] < clamped) {  // exact from the band
          previous = static_cast<double>(row[i]) * s.to_model;
          continue;
        }
        const dvec3 p(centre_coordinate(g, 0, i), cy, cz);
        // The margin covers the float rounding of band values and of the
        // centres' spacing.
        const double bound = previous >= 0.0 ? (previous + g.voxel_size) * (1.0 + 1e-6) : kInfinity;
        TriangleTree::Hit hit = tree.nearest(p, bound * bound, hint);
        if (hit.triangle == TriangleTree::kNone) hit = tree.nearest(p, kInfinity, TriangleTree::kNone);
        if (hit.triangle == TriangleTree::kNone) continue;  // no triangles at all: stays clamped
        previous = std::sqrt(hit.d2);
        hint = hit.triangle;
        row[i] = static_cast<float>(previous * s.to_output);
      }
    }
    queries.report(static_cast<double>(done.fetch_add(r1 - r0) + (r1 - r0)) / static_cast<double>(rows));
  });
  queries.report(1.0);
}

// ---------------------------------------------------------------------------

// The solid voxelization for the sign, on a JobControl of its own: the
// voxelizers report 0..1 on the control they get, and a JobControl's span
// belongs to whoever runs the job, so it cannot be narrowed here. A watcher
// forwards cancellation in and progress (onto `progress`) out.
BitVolume solid_for_sign(const Mesh& mesh, const Grid& grid, const SdfOptions& options,
                         const detail::ProgressSpan& progress) {
  const VoxelizeOptions vo{VoxelMode::solid, options.inside, options.threads};
  if (!progress.control) return voxelize(mesh, grid, vo, nullptr);
  JobControl inner;
  std::mutex mutex;
  std::condition_variable wake;
  bool finished = false;
  std::thread watcher([&] {
    std::unique_lock lock(mutex);
    while (!wake.wait_for(lock, std::chrono::milliseconds(2), [&] { return finished; })) {
      if (progress.control->cancel_requested()) inner.request_cancel();
      progress.report(inner.progress());
    }
  });
  auto stop = [&] {
    {
      std::lock_guard lock(mutex);
      finished = true;
    }
    wake.notify_one();
    watcher.join();
  };
  BitVolume solid;
  try {
    solid = voxelize(mesh, grid, vo, &inner);
  } catch (...) {
    stop();
    throw;
  }
  stop();
  progress.check_cancelled();
  progress.report(1.0);
  return solid;
}

}  // namespace

double point_triangle_distance2(const dvec3& p, const dvec3& a, const dvec3& b, const dvec3& c) {
  return distance2(Triangle(a, b, c), p);
}

DenseVolume<float> signed_distance_field(const Mesh& mesh, const Grid& grid, const SdfOptions& options,
                                         JobControl* control) {
  if (!(options.band > 0.0) || !std::isfinite(options.band))
    throw Error(ErrorCode::invalid_argument, "the distance band must be a positive number of voxels");
  if (!(grid.voxel_size > 0.0) || !std::isfinite(grid.voxel_size))
    throw Error(ErrorCode::invalid_argument, "the voxel size must be a positive number");
  const int threads = options.threads > 0 ? options.threads : default_thread_count();
  const detail::ProgressSpan progress{control, 0.0, 1.0};

  BandSetup s;
  s.band = options.band * grid.voxel_size;
  s.to_model = options.model_units ? 1.0 : grid.voxel_size;
  s.to_output = options.model_units ? 1.0 : 1.0 / grid.voxel_size;
  // Exactly +-band in the output unit, not band * voxel_size / voxel_size.
  const auto clamped = static_cast<float>(options.model_units ? s.band : options.band);

  DenseVolume<float> values(grid, clamped);
  if (grid.voxel_count() == 0) return values;
  const double band_end = options.full ? 0.25 : 1.0;
  const BitVolume solid = solid_for_sign(mesh, grid, options, progress.part(0.0, 0.15));
  scatter_band(mesh, grid, s, threads, values, progress.part(0.15, band_end));
  if (options.full) fill_beyond_band(mesh, grid, s, clamped, threads, values, progress.part(band_end, 1.0));

  // Sign; a value of 0 (a centre on the surface) stays +0.
  const bool negate_inside = options.sign == SignConvention::inside_negative;
  const std::int64_t nx = grid.dims.x, ny = grid.dims.y;
  parallel_for(0, grid.dims.z, 1, threads, [&](std::int64_t k0, std::int64_t k1) {
    for (std::int64_t k = k0; k < k1; ++k)
      for (std::int64_t j = 0; j < ny; ++j) {
        float* row = values.slab(k) + j * nx;
        for (std::int64_t i = 0; i < nx; ++i)
          if (row[i] != 0.0f && solid.get(i, j, k) == negate_inside) row[i] = -row[i];
      }
  });
  progress.report(1.0);
  return values;
}

}  // namespace voxd
