// The mesh report: geometry sums in double, and edge topology on the welded
// mesh. Edges are grouped by a counting sort on their smaller vertex rather
// than hashed: every edge lands in its vertex's short bucket, so the whole
// pass is two linear sweeps plus tiny sorts.
#include <algorithm>
#include <vector>

#include <glm/geometric.hpp>

#include "voxd/mesh_report.h"

namespace voxd {
namespace {

bool repeats_a_vertex(const std::array<std::uint32_t, 3>& t) { return t[0] == t[1] || t[1] == t[2] || t[0] == t[2]; }

void add_geometry(const Mesh& welded, MeshReport& report) {
  // Volume terms are taken about the box centre: for a closed mesh the result
  // is the same, with far less cancellation when the model sits far from 0.
  const glm::dvec3 origin = report.bbox.center();
  double twice_area = 0.0, six_volume = 0.0;
  for (const auto& t : welded.triangles) {
    const glm::dvec3 a(welded.vertices[t[0]]), b(welded.vertices[t[1]]), c(welded.vertices[t[2]]);
    // Differences and products of floats are exact in double, so a zero
    // normal means exactly repeated or collinear corners.
    const glm::dvec3 normal = glm::cross(b - a, c - a);
    if (normal == glm::dvec3(0.0)) ++report.degenerate_triangles;
    twice_area += glm::length(normal);
    six_volume += glm::dot(a - origin, normal);
  }
  report.surface_area = twice_area / 2.0;
  report.volume = six_volume / 6.0;
}

// Sorts a vertex's bucket of edges; buckets are tiny except around a fan
// centre, where insertion sort would go quadratic.
void sort_bucket(std::uint64_t* first, std::uint64_t* last) {
  if (last - first < 2) return;  // also an empty bucket of an empty array (null first)
  if (last - first > 32) {
    std::sort(first, last);
    return;
  }
  for (std::uint64_t* i = first + 1; i < last; ++i) {
    const std::uint64_t value = *i;
    std::uint64_t* j = i;
    for (; j > first && *(j - 1) > value; --j) *j = *(j - 1);
    *j = value;
  }
}

void add_edge_topology(const Mesh& welded, MeshReport& report) {
  // Triangles that repeat a welded vertex have no area and would count one
  // edge twice in opposite directions; they take no part in the topology.
  const std::size_t vertex_count = welded.vertices.size();
  std::vector<std::size_t> bucket_start(vertex_count + 1, 0);
  for (const auto& t : welded.triangles) {
    if (repeats_a_vertex(t)) continue;
    for (int c = 0; c < 3; ++c) ++bucket_start[std::min(t[c], t[(c + 1) % 3]) + 1];
  }
  for (std::size_t v = 0; v < vertex_count; ++v) bucket_start[v + 1] += bucket_start[v];

  // Each use of an edge is stored in the bucket of its smaller vertex as
  // (larger vertex << 1 | 1 if traversed from smaller to larger).
  std::vector<std::uint64_t> uses(bucket_start[vertex_count]);
  std::vector<std::size_t> cursor(bucket_start.begin(), bucket_start.end() - 1);
  for (const auto& t : welded.triangles) {
    if (repeats_a_vertex(t)) continue;
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t from = t[c], to = t[(c + 1) % 3];
      const std::uint32_t low = std::min(from, to), high = std::max(from, to);
      uses[cursor[low]++] = std::uint64_t{high} << 1 | (from == low ? 1u : 0u);
    }
  }

  // No usable edge (every triangle repeats a vertex): uses.data() may be null.
  if (uses.empty()) {
    report.watertight = false;
    return;
  }
  for (std::size_t v = 0; v < vertex_count; ++v) {
    std::uint64_t* first = uses.data() + bucket_start[v];
    std::uint64_t* const last = uses.data() + bucket_start[v + 1];
    sort_bucket(first, last);
    while (first < last) {
      const std::uint64_t edge = *first >> 1;
      std::uint64_t count = 0, forward = 0;
      for (; first < last && (*first >> 1) == edge; ++first) {
        ++count;
        forward += *first & 1;
      }
      if (count == 1) ++report.boundary_edges;
      else if (count > 2) ++report.nonmanifold_edges;
      else if (forward != 1) ++report.inconsistent_edges;
    }
  }
  // Watertight means the volume can be trusted: closed, manifold and
  // consistently oriented (an inconsistent edge is a flipped triangle, which
  // the divergence theorem counts with the wrong sign). Degenerate triangles
  // neither open nor turn the surface, so they are only counted.
  report.watertight = report.boundary_edges == 0 && report.nonmanifold_edges == 0 && report.inconsistent_edges == 0;
}

std::uint64_t count_referenced(const Mesh& mesh) {
  std::vector<bool> used(mesh.vertices.size(), false);
  std::uint64_t count = 0;
  for (const auto& t : mesh.triangles)
    for (std::uint32_t v : t)
      if (!used[v]) {
        used[v] = true;
        ++count;
      }
  return count;
}

}  // namespace

MeshReport make_mesh_report(const Mesh& mesh) {
  if (mesh.triangles.empty()) return {};  // nothing is closed, nothing has volume
  return mesh_report_of_welded(weld_vertices(mesh));
}

MeshReport mesh_report_of_welded(const Mesh& welded) {
  MeshReport report;
  report.triangles = welded.triangles.size();  // welding keeps every triangle
  if (welded.triangles.empty()) return report;
  // Unreferenced vertices (some formats keep them) are not part of the surface.
  report.vertices = count_referenced(welded);
  report.bbox = bounds(welded);
  add_geometry(welded, report);
  add_edge_topology(welded, report);
  return report;
}

}  // namespace voxd
