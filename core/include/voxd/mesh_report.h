#pragma once
// Topology and geometry report of a mesh: what a user needs to know before
// trusting a voxelization (is it closed? oriented? how big?).
#include <cstdint>
#include <string>
#include <vector>

#include <optional>

#include "voxd/edge_topology.h"
#include "voxd/mesh.h"
#include "voxd/mesh_orientation.h"

namespace voxd {

struct MeshReport {
  std::uint64_t triangles = 0;            // as decoded
  std::uint64_t vertices = 0;             // after welding identical positions
  Aabb bbox;
  std::uint64_t degenerate_triangles = 0; // zero area (repeated or collinear corners)
  std::uint64_t boundary_edges = 0;       // edges used by exactly one triangle
  std::uint64_t nonmanifold_edges = 0;    // edges used by more than two triangles
  std::uint64_t inconsistent_edges = 0;   // manifold edges traversed in the same direction twice
  bool watertight = false;                // has edges, none boundary, non-manifold or inconsistent
  double surface_area = 0.0;
  double volume = 0.0;                    // signed, by the divergence theorem; meaningful when watertight
  // What decoding the file noticed (DecodeWarnings): set by whoever decoded
  // it, as make_mesh_report sees only the mesh.
  std::vector<std::string> warnings;
  // What orienting the mesh turned round (orient_outward), when it was: set
  // by whoever oriented it. The counts above are then of the mesh as
  // oriented, which is the mesh that was voxelized.
  std::optional<OrientationRepair> orientation;
};

// Merges vertices with bit-identical positions; triangles keep their order.
Mesh weld_vertices(const Mesh& mesh);

// Welds internally, so a triangle soup gives the same report as its indexed twin.
MeshReport make_mesh_report(const Mesh& mesh);
// The same report from weld_vertices(mesh), for a caller that has it, and
// its edge_topology_of_welded when the caller has that too.
MeshReport mesh_report_of_welded(const Mesh& welded, const EdgeTopology* topology = nullptr);

}  // namespace voxd
