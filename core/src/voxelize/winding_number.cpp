#include "voxd/voxelize/winding_number.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <functional>
#include <limits>
#include <numbers>

#include <glm/geometric.hpp>

#include "voxd/progress.h"

namespace voxd {
namespace {

constexpr double kFourPi = 4.0 * std::numbers::pi;
// Triangles per BVH leaf: small enough that near-field exact sums stay short,
// large enough that the tree (and its expansion coefficients) stays small.
constexpr std::uint32_t kLeafSize = 8;
// Construction checks for cancellation about every this many triangles or
// sorted elements (a millisecond of work or less).
constexpr std::uint32_t kCancelCheckInterval = 1 << 15;
// Median splits halve the range, so depth <= log2(2^32 / kLeafSize) + 1 < 64.
constexpr int kStackSize = 128;

// Signed solid angle of triangle (a, b, c) seen from the origin, by Van
// Oosterom and Strackee: tan(Omega/2) = det[a b c] / (|a||b||c| + (a.b)|c| +
// (b.c)|a| + (c.a)|b|). When det is 0 the origin is in the triangle's plane
// (or the triangle is degenerate): the solid angle is 0 outside the triangle
// and jumps between +2pi and -2pi across it, so 0, the average of the two
// sides, is returned in every case. This avoids atan2 turning the arbitrary
// sign of a zero determinant into +-pi, makes w on a face exactly the mean of
// the values on either side (1/2 on a closed mesh), and never yields NaN: at a
// vertex det is 0 too.
double solid_angle(glm::dvec3 a, glm::dvec3 b, glm::dvec3 c) {
  const double det = glm::dot(a, glm::cross(b, c));
  if (det == 0.0) return 0.0;
  const double la = glm::length(a), lb = glm::length(b), lc = glm::length(c);
  const double den = la * lb * lc + glm::dot(a, b) * lc + glm::dot(b, c) * la + glm::dot(c, a) * lb;
  return 2.0 * std::atan2(det, den);
}

void checkpoint(const JobControl* control) {
  if (control) control->check_cancelled();
}

// std::sort in cancellable steps: sorted runs, then rounds of pairwise
// merges, checking for cancellation between steps. The longest unchecked step
// is the final merge, a linear pass (~30 ms for 4M elements) rather than a
// whole O(n log n) sort.
template <class T, class Less>
void sort_cancellable(std::vector<T>& v, Less less, const JobControl* control) {
  constexpr std::size_t kRun = 1 << 15;
  const std::size_t n = v.size();
  for (std::size_t b = 0; b < n; b += kRun) {
    checkpoint(control);
    std::sort(v.begin() + static_cast<std::ptrdiff_t>(b), v.begin() + static_cast<std::ptrdiff_t>(std::min(n, b + kRun)),
              less);
  }
  for (std::size_t width = kRun; width < n; width *= 2) {
    for (std::size_t b = 0; b + width < n; b += 2 * width) {
      checkpoint(control);
      std::inplace_merge(v.begin() + static_cast<std::ptrdiff_t>(b), v.begin() + static_cast<std::ptrdiff_t>(b + width),
                         v.begin() + static_cast<std::ptrdiff_t>(std::min(n, b + 2 * width)), less);
    }
  }
}

double squared_distance_to_segment(glm::dvec3 p, glm::dvec3 a, glm::dvec3 b) {
  const glm::dvec3 ab = b - a, ap = p - a;
  const double len2 = glm::dot(ab, ab);
  const double t = len2 > 0.0 ? std::clamp(glm::dot(ap, ab) / len2, 0.0, 1.0) : 0.0;
  const glm::dvec3 d = ap - t * ab;
  return glm::dot(d, d);
}

// Distance to the infinite line through a and b (0 for a zero-length edge,
// which makes the caller fall back to its other bound).
double distance_to_line(glm::dvec3 p, glm::dvec3 a, glm::dvec3 b) {
  const glm::dvec3 ab = b - a, ap = p - a;
  const double len2 = glm::dot(ab, ab);
  if (len2 <= 0.0) return 0.0;
  const double along = glm::dot(ap, ab);
  return std::sqrt(std::max(0.0, glm::dot(ap, ap) - along * along / len2));
}

// Squared distance from p to the closed triangle. Written as "nearest edge,
// or the plane when p projects inside" rather than with barycentric region
// tests, so that degenerate (zero-area) triangles need no special division.
double squared_distance_to_triangle(glm::dvec3 p, glm::dvec3 a, glm::dvec3 b, glm::dvec3 c) {
  double best = std::min({squared_distance_to_segment(p, a, b), squared_distance_to_segment(p, b, c),
                          squared_distance_to_segment(p, c, a)});
  const glm::dvec3 n = glm::cross(b - a, c - a);
  const double nn = glm::dot(n, n);
  if (nn > 0.0) {
    const double s = glm::dot(p - a, n);
    const glm::dvec3 q = p - n * (s / nn);
    if (glm::dot(glm::cross(b - a, q - a), n) >= 0.0 && glm::dot(glm::cross(c - b, q - b), n) >= 0.0 &&
        glm::dot(glm::cross(a - c, q - c), n) >= 0.0)
      best = std::min(best, s * s / nn);
  }
  return best;
}

double squared_distance_to_box(glm::dvec3 p, glm::dvec3 lo, glm::dvec3 hi) {
  const glm::dvec3 d = glm::max(glm::max(lo - p, p - hi), glm::dvec3(0.0));
  return glm::dot(d, d);
}

// For every triangle corner e (edge from corner e to corner e+1), how many
// times that edge belongs to the boundary curve of the soup. Vertices are
// matched by position, not index, so an unwelded soup (STL) whose triangles
// meet exactly is recognised as closed. Each undirected edge gets the net
// count of its directed occurrences (+1 one way, -1 the other); a nonzero net
// is booked, in absolute value, on the first triangle corner that has it.
std::vector<std::array<std::uint32_t, 3>> boundary_multiplicities(const Mesh& mesh, const JobControl* control) {
  // Position ids: equal coordinates (as floats) share an id.
  std::vector<std::uint32_t> by_position(mesh.vertices.size());
  for (std::uint32_t i = 0; i < by_position.size(); ++i) by_position[i] = i;
  auto less = [&](std::uint32_t l, std::uint32_t r) {
    const glm::vec3 a = mesh.vertices[l], b = mesh.vertices[r];
    if (a.x != b.x) return a.x < b.x;
    if (a.y != b.y) return a.y < b.y;
    return a.z < b.z;
  };
  sort_cancellable(by_position, less, control);
  std::vector<std::uint32_t> position_id(mesh.vertices.size());
  std::uint32_t next_id = 0;
  for (std::size_t i = 0; i < by_position.size(); ++i) {
    if (i > 0 && less(by_position[i - 1], by_position[i])) ++next_id;
    position_id[by_position[i]] = next_id;
  }

  // One entry per directed edge: (undirected key, corner * 2 + direction),
  // key = (smaller id << 32) | larger id, corner = 3 * triangle + e,
  // direction 1 from the smaller id to the larger, 0 the other way.
  std::vector<std::pair<std::uint64_t, std::uint64_t>> edges;
  edges.reserve(mesh.triangles.size() * 3);
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    if (t % kCancelCheckInterval == 0) checkpoint(control);
    for (std::uint32_t e = 0; e < 3; ++e) {
      const std::uint32_t p = position_id[mesh.triangles[t][e]];
      const std::uint32_t q = position_id[mesh.triangles[t][(e + 1) % 3]];
      if (p == q) continue;  // zero length: no contribution to any line integral
      const std::uint64_t key = (std::uint64_t{std::min(p, q)} << 32) | std::max(p, q);
      edges.emplace_back(key, (std::uint64_t{3} * t + e) * 2 + (p < q ? 1 : 0));
    }
  }
  sort_cancellable(edges, std::less<>(), control);
  checkpoint(control);

  std::vector<std::array<std::uint32_t, 3>> multiplicity(mesh.triangles.size(), {0, 0, 0});
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    long net = 0;
    for (; j < edges.size() && edges[j].first == edges[i].first; ++j) net += (edges[j].second & 1) ? 1 : -1;
    if (net != 0) {
      const std::uint64_t corner = edges[i].second / 2;
      multiplicity[corner / 3][corner % 3] = static_cast<std::uint32_t>(std::labs(net));
    }
    i = j;
  }
  return multiplicity;
}

}  // namespace

WindingNumberField::WindingNumberField(const Mesh& mesh, double beta, const JobControl* control) : beta_(beta) {
  const std::size_t n = mesh.triangles.size();
  if (n == 0) return;
  const auto multiplicity = boundary_multiplicities(mesh, control);

  std::vector<glm::dvec3> centroids(n);
  for (std::size_t t = 0; t < n; ++t)
    centroids[t] = (glm::dvec3(mesh.corner(t, 0)) + glm::dvec3(mesh.corner(t, 1)) + glm::dvec3(mesh.corner(t, 2))) / 3.0;
  std::vector<std::uint32_t> order(n);
  for (std::uint32_t t = 0; t < n; ++t) order[t] = t;
  nodes_.reserve(2 * (n / kLeafSize + 1));
  build(order, 0, static_cast<std::uint32_t>(n), centroids, control);

  triangles_.reserve(n);
  for (std::uint32_t t : order) {
    if (triangles_.size() % kCancelCheckInterval == 0) checkpoint(control);
    Triangle tri{mesh.corner(t, 0), mesh.corner(t, 1), mesh.corner(t, 2),
                 {multiplicity[t][0], multiplicity[t][1], multiplicity[t][2]}};
    triangles_.push_back(tri);
  }
  compute_expansions(control);
}

// Top-down median split along the longest axis of the centroids' box. Only the
// topology and triangle ranges are decided here; the geometry per node is
// filled by compute_expansions once triangles_ is in leaf order.
std::uint32_t WindingNumberField::build(std::vector<std::uint32_t>& order, std::uint32_t begin, std::uint32_t end,
                                        const std::vector<glm::dvec3>& centroids, const JobControl* control) {
  if (end - begin >= kCancelCheckInterval) checkpoint(control);
  const auto index = static_cast<std::uint32_t>(nodes_.size());
  nodes_.emplace_back();
  nodes_[index].begin = begin;
  nodes_[index].end = end;
  if (end - begin <= kLeafSize) return index;

  glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
  for (std::uint32_t i = begin; i < end; ++i) {
    lo = glm::min(lo, centroids[order[i]]);
    hi = glm::max(hi, centroids[order[i]]);
  }
  const glm::dvec3 extent = hi - lo;
  const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : extent.y >= extent.z ? 1 : 2;
  const std::uint32_t mid = begin + (end - begin) / 2;
  std::nth_element(order.begin() + begin, order.begin() + mid, order.begin() + end,
                   [&](std::uint32_t l, std::uint32_t r) { return centroids[l][axis] < centroids[r][axis]; });
  build(order, begin, mid, centroids, control);
  const std::uint32_t right = build(order, mid, end, centroids, control);
  nodes_[index].right = right;
  return index;
}

namespace {

// A node's expansion coefficients about its own centre, kept unsymmetrised
// so that a parent can translate its children's to its centre instead of
// revisiting every triangle (O(n) for the tree instead of O(n log n)).
struct Moments {
  double area = 0.0;
  glm::dvec3 centroid_sum{0.0};  // sum of area * centroid
  glm::dvec3 dipole{0.0};        // N_i = sum of area * n_i
  double first[3][3] = {};       // C_ij = sum of area * n_i * (centroid - center)_j
  double second[3][6] = {};      // T_i,jk = sum of area * n_i * M_jk, jk as xx, yy, zz, xy, xz, yz
};

constexpr int kPairJ[6] = {0, 1, 2, 0, 0, 1};
constexpr int kPairK[6] = {0, 1, 2, 1, 2, 2};

}  // namespace

// Children first: nodes are in depth-first order, so every child has a
// larger index than its parent and a reverse sweep sees children first.
void WindingNumberField::compute_expansions(const JobControl* control) {
  std::vector<Moments> moments(nodes_.size());
  for (std::size_t index = nodes_.size(); index-- > 0;) {
    if (index % (kCancelCheckInterval / kLeafSize) == 0) checkpoint(control);
    Node& node = nodes_[index];
    Moments& m = moments[index];
    if (node.leaf()) {
      glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
      for (std::uint32_t i = node.begin; i < node.end; ++i) {
        const Triangle& t = triangles_[i];
        const glm::dvec3 p0(t.a), p1(t.b), p2(t.c);
        lo = glm::min(glm::min(lo, p0), glm::min(p1, p2));
        hi = glm::max(glm::max(hi, p0), glm::max(p1, p2));
        const glm::dvec3 vector_area = 0.5 * glm::cross(p1 - p0, p2 - p0);
        const double a = glm::length(vector_area);
        m.area += a;
        m.centroid_sum += a * (p0 + p1 + p2) / 3.0;
        m.dipole += vector_area;
        node.boundary_length += t.boundary_multiplicity[0] * glm::distance(p0, p1) +
                                t.boundary_multiplicity[1] * glm::distance(p1, p2) +
                                t.boundary_multiplicity[2] * glm::distance(p2, p0);
      }
      node.box_min = lo;
      node.box_max = hi;
      // All-degenerate nodes have no area to weight by; any point inside works.
      node.center = m.area > 0.0 ? m.centroid_sum / m.area : (lo + hi) * 0.5;
      for (std::uint32_t i = node.begin; i < node.end; ++i) {
        const Triangle& t = triangles_[i];
        const glm::dvec3 p0(t.a), p1(t.b), p2(t.c);
        const glm::dvec3 e[3] = {p0 - node.center, p1 - node.center, p2 - node.center};
        const glm::dvec3 vector_area = 0.5 * glm::cross(p1 - p0, p2 - p0);
        const glm::dvec3 sum = e[0] + e[1] + e[2];
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) m.first[r][c] += vector_area[r] * sum[c] / 3.0;
        // Second moment of a triangle with corners e0, e1, e2 relative to the
        // centre: integral of x x^T = area/12 * (sum of e e^T + s s^T), s = e0 + e1 + e2.
        for (int jk = 0; jk < 6; ++jk) {
          const int j = kPairJ[jk], k = kPairK[jk];
          const double moment = (e[0][j] * e[0][k] + e[1][j] * e[1][k] + e[2][j] * e[2][k] + sum[j] * sum[k]) / 12.0;
          for (int r = 0; r < 3; ++r) m.second[r][jk] += vector_area[r] * moment;
        }
      }
    } else {
      const Node& left = nodes_[index + 1];
      const Node& right = nodes_[node.right];
      const Moments& ml = moments[index + 1];
      const Moments& mr = moments[node.right];
      node.box_min = glm::min(left.box_min, right.box_min);
      node.box_max = glm::max(left.box_max, right.box_max);
      node.boundary_length = left.boundary_length + right.boundary_length;
      m.area = ml.area + mr.area;
      m.centroid_sum = ml.centroid_sum + mr.centroid_sum;
      m.dipole = ml.dipole + mr.dipole;
      node.center = m.area > 0.0 ? m.centroid_sum / m.area : (node.box_min + node.box_max) * 0.5;
      // Moving the expansion point from the child's centre by
      // delta = child centre - centre, with x - centre = (x - child centre) + delta:
      //   C_ij  += C'_ij + N'_i delta_j
      //   T_ijk += T'_ijk + C'_ij delta_k + C'_ik delta_j + N'_i delta_j delta_k
      for (const auto& [child, cm] : {std::pair{&left, &ml}, std::pair{&right, &mr}}) {
        const glm::dvec3 delta = child->center - node.center;
        for (int i = 0; i < 3; ++i) {
          for (int j = 0; j < 3; ++j) m.first[i][j] += cm->first[i][j] + cm->dipole[i] * delta[j];
          for (int jk = 0; jk < 6; ++jk) {
            const int j = kPairJ[jk], k = kPairK[jk];
            m.second[i][jk] += cm->second[i][jk] + cm->first[i][j] * delta[k] + cm->first[i][k] * delta[j] +
                               cm->dipole[i] * delta[j] * delta[k];
          }
        }
      }
    }

    // The radius is measured, not bounded from the children's: a looser
    // radius would push evaluations into more exact near-field sums.
    double radius2 = 0.0;
    for (std::uint32_t i = node.begin; i < node.end; ++i) {
      const Triangle& t = triangles_[i];
      for (const glm::vec3& v : {t.a, t.b, t.c}) {
        const glm::dvec3 e = glm::dvec3(v) - node.center;
        radius2 = std::max(radius2, glm::dot(e, e));
      }
    }
    node.radius = std::sqrt(radius2);
    node.dipole = m.dipole;
    node.first_order[0] = m.first[0][0];
    node.first_order[1] = m.first[1][1];
    node.first_order[2] = m.first[2][2];
    node.first_order[3] = 0.5 * (m.first[0][1] + m.first[1][0]);
    node.first_order[4] = 0.5 * (m.first[0][2] + m.first[2][0]);
    node.first_order[5] = 0.5 * (m.first[1][2] + m.first[2][1]);
    std::copy(&m.second[0][0], &m.second[0][0] + 18, &node.second_order[0][0]);
    // What the kernel contracts T with (see operator()): per k,
    // 2 * sum_i T_iik + sum_j T_kjj.
    const auto& t = m.second;
    for (int k = 0; k < 3; ++k) node.second_order_traces[k] = t[k][0] + t[k][1] + t[k][2];
    node.second_order_traces.x += 2.0 * (t[0][0] + t[1][3] + t[2][4]);
    node.second_order_traces.y += 2.0 * (t[0][3] + t[1][1] + t[2][5]);
    node.second_order_traces.z += 2.0 * (t[0][4] + t[1][5] + t[2][2]);
  }
}

namespace {

// y^T S y for a symmetric matrix stored as xx, yy, zz, xy, xz, yz.
double quadratic_form(const double* s, glm::dvec3 y) {
  return s[0] * y.x * y.x + s[1] * y.y * y.y + s[2] * y.z * y.z +
         2.0 * (s[3] * y.x * y.y + s[4] * y.x * y.z + s[5] * y.y * y.z);
}

}  // namespace

// Far field: each triangle contributes the integral over t of
// n.(x - q)/|x - q|^3. With y = center - q and x = center + d, expand
// f(y + d) = (y + d)/|y + d|^3 to second order in d:
//   f(y) + J d + 1/2 H[d, d],  J_ij = d_j f_i = delta_ij/r^3 - 3 y_i y_j/r^5,
//   H_ijk = d_j d_k f_i = -3 (delta_ij y_k + delta_ik y_j + delta_jk y_i)/r^5 + 15 y_i y_j y_k/r^7.
// Integrated over the node's triangles (area * n_i times the moments of d):
//   order 0: dipole.y / r^3
//   order 1: sum_ij J_ij C_ij = trace(C)/r^3 - 3 y^T C y/r^5
//   order 2: 1/2 sum_ijk H_ijk T_ijk = -3/2 (2 sum T_iik y_k + sum T_ijj y_i)/r^5
//                                     + 15/2 sum y_i y_j y_k T_ijk / r^7.
// The truncation error falls as (node radius / distance)^3 relative to the
// node's dipole term; beta bounds that ratio.
double WindingNumberField::operator()(glm::dvec3 p) const {
  if (nodes_.empty()) return 0.0;
  const double beta2 = beta_ * beta_;
  double total = 0.0;  // sum of solid angles
  std::array<std::uint32_t, kStackSize> stack;
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    const glm::dvec3 y = node.center - p;
    const double r2 = glm::dot(y, y);
    if (r2 > beta2 * node.radius * node.radius) {
      const double inv_r2 = 1.0 / r2;
      const double inv_r3 = inv_r2 / std::sqrt(r2);
      const double inv_r5 = inv_r3 * inv_r2;
      const double* c = node.first_order;
      const double order0 = glm::dot(node.dipole, y) * inv_r3;
      const double order1 = (c[0] + c[1] + c[2]) * inv_r3 - 3.0 * quadratic_form(c, y) * inv_r5;
      const double cubic = y.x * quadratic_form(node.second_order[0], y) +
                           y.y * quadratic_form(node.second_order[1], y) +
                           y.z * quadratic_form(node.second_order[2], y);
      const double order2 = -1.5 * glm::dot(node.second_order_traces, y) * inv_r5 + 7.5 * cubic * inv_r5 * inv_r2;
      total += order0 + order1 + order2;
    } else if (node.leaf()) {
      for (std::uint32_t i = node.begin; i < node.end; ++i) {
        const Triangle& t = triangles_[i];
        total += solid_angle(glm::dvec3(t.a) - p, glm::dvec3(t.b) - p, glm::dvec3(t.c) - p);
      }
    } else {
      stack[top++] = node.right;
      stack[top++] = static_cast<std::uint32_t>(&node - nodes_.data()) + 1;
    }
  }
  return total / kFourPi;
}

bool WindingNumberField::surface_within(glm::dvec3 center, double radius) const {
  if (nodes_.empty()) return false;
  // Err towards "yes": a false yes only costs the caller a finer look.
  const double r2 = radius * radius * (1.0 + 1e-9);
  std::array<std::uint32_t, kStackSize> stack;
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const std::uint32_t index = stack[--top];
    const Node& node = nodes_[index];
    if (squared_distance_to_box(center, node.box_min, node.box_max) > r2) continue;
    if (node.leaf()) {
      for (std::uint32_t i = node.begin; i < node.end; ++i) {
        const Triangle& t = triangles_[i];
        if (squared_distance_to_triangle(center, glm::dvec3(t.a), glm::dvec3(t.b), glm::dvec3(t.c)) <= r2) return true;
      }
    } else {
      stack[top++] = node.right;
      stack[top++] = index + 1;
    }
  }
  return false;
}

// Why this bounds the variation: off the surface, the gradient of a
// triangle's solid angle is the Biot-Savart integral over its boundary loop,
// grad Omega(x) = +-(loop integral of (y - x) x dy / |y - x|^3). Summed over
// the soup, an edge traversed once each way cancels, so only the boundary
// curve (edges with nonzero net multiplicity) remains, and
//   |grad w(x)| <= 1/(4 pi) * sum_e m_e * integral_e |dy| / |y - x|^2.
// For x in a triangle-free ball B(center, radius), w is smooth in B and, B
// being convex, |w(x) - w(center)| <= radius * sup_B |grad w|. Each edge term
// at any x in B is at most len / (dist(center, e) - radius)^2, and also at
// most pi / (dist(center, line of e) - radius) (the integral over the whole
// line). A node's edges are all at least its box distance away, so a far
// node contributes at most boundary_length / (box distance - radius)^2.
double WindingNumberField::variation_bound(glm::dvec3 center, double radius, double limit) const {
  if (closed() || radius <= 0.0) return 0.0;
  constexpr double inf = std::numeric_limits<double>::infinity();
  const double scale = radius / kFourPi;
  const double budget = limit / scale;  // stop once the integral sum passes this
  double sum = 0.0;
  std::array<std::uint32_t, kStackSize> stack;
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const std::uint32_t index = stack[--top];
    const Node& node = nodes_[index];
    if (node.boundary_length == 0.0) continue;
    const double gap = std::sqrt(squared_distance_to_box(center, node.box_min, node.box_max)) - radius;
    if (node.leaf()) {
      for (std::uint32_t i = node.begin; i < node.end; ++i) {
        const Triangle& t = triangles_[i];
        const glm::dvec3 corners[3] = {glm::dvec3(t.a), glm::dvec3(t.b), glm::dvec3(t.c)};
        for (int e = 0; e < 3; ++e) {
          if (t.boundary_multiplicity[e] == 0) continue;
          const glm::dvec3 a = corners[e], b = corners[(e + 1) % 3];
          const double edge_gap = std::sqrt(squared_distance_to_segment(center, a, b)) - radius;
          if (edge_gap <= 0.0) return inf;
          double term = glm::distance(a, b) / (edge_gap * edge_gap);
          const double line_gap = distance_to_line(center, a, b) - radius;
          if (line_gap > 0.0) term = std::min(term, std::numbers::pi / line_gap);
          sum += t.boundary_multiplicity[e] * term;
        }
      }
    } else if (gap > glm::distance(node.box_min, node.box_max)) {
      sum += node.boundary_length / (gap * gap);
    } else {
      // Too close for the aggregate bound to be tight: look at the children.
      stack[top++] = node.right;
      stack[top++] = index + 1;
    }
    if (sum > budget) return scale * sum;
  }
  return scale * sum;
}

double winding_number_exact(const Mesh& mesh, glm::dvec3 p) {
  double total = 0.0;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    total += solid_angle(glm::dvec3(mesh.corner(t, 0)) - p, glm::dvec3(mesh.corner(t, 1)) - p,
                         glm::dvec3(mesh.corner(t, 2)) - p);
  return total / kFourPi;
}

}  // namespace voxd
