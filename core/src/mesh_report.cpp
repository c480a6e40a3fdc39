// The mesh report: geometry sums in double, and edge topology on the welded
// mesh (edge_topology_of_welded).
#include <algorithm>
#include <vector>

#include <glm/geometric.hpp>

#include "voxd/edge_topology.h"
#include "voxd/mesh_report.h"

namespace voxd {
namespace {

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

void add_edge_topology(const EdgeTopology& topology, MeshReport& report) {
  report.boundary_edges = topology.boundary_edges;
  report.nonmanifold_edges = topology.nonmanifold_edges;
  report.inconsistent_edges = topology.inconsistent_edges;
  // Watertight means the volume can be trusted: closed, manifold and
  // consistently oriented (an inconsistent edge is a flipped triangle, which
  // the divergence theorem counts with the wrong sign). Degenerate triangles
  // neither open nor turn the surface, so they are only counted. No usable
  // edge (every triangle repeats a vertex) is not watertight either.
  report.watertight = topology.edges > 0 && topology.boundary_edges == 0 && topology.nonmanifold_edges == 0 &&
                      topology.inconsistent_edges == 0;
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

MeshReport mesh_report_of_welded(const Mesh& welded, const EdgeTopology* topology) {
  MeshReport report;
  report.triangles = welded.triangles.size();  // welding keeps every triangle
  if (welded.triangles.empty()) return report;
  // Unreferenced vertices (some formats keep them) are not part of the surface.
  report.vertices = count_referenced(welded);
  report.bbox = bounds(welded);
  add_geometry(welded, report);
  add_edge_topology(topology ? *topology : edge_topology_of_welded(welded), report);
  return report;
}

}  // namespace voxd
