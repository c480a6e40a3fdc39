// The oriented-box hierarchy of sdf_tree.h: build and nearest-triangle query.
#include "voxelize/sdf_tree.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>

#include "voxd/error.h"
#include "voxd/parallel.h"

namespace voxd::sdf {
namespace {

// Rounds up to a float, with a relative margin that absorbs the rounding of
// the double arithmetic in lower_bound2.
inline float round_up(double v) {
  const auto f = static_cast<float>(v * (1.0 + 1e-6));
  return static_cast<double>(f) >= v ? f : std::nextafter(f, std::numeric_limits<float>::infinity());
}


}  // namespace

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

}  // namespace voxd::sdf
