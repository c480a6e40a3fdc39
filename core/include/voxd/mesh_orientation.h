#pragma once
// Orienting a mesh's triangles so that their normals point out of the solid
// they bound: what the winding number and a distance field's sign need, and
// what real files often get wrong (a whole part written inside out, or some
// triangles flipped against their neighbours). Parity does not care, which is
// why only those inside tests ask for it.
//
// The method: weld by exact position, then propagate one orientation across
// each manifold edge (two triangles), breadth first, which splits the mesh
// into edge-connected components, each consistent with itself. Each
// component keeps the orientation most of its area had as written (a few
// flipped triangles are the error, not the rest). Then each component's sign:
// its signed volume about its own centroid is positive for a solid and
// negative for a cavity, and whether it should be a cavity comes from how
// many other components enclose it (ray parity against them, the majority
// of three rays, so that an enclosure with a hole still counts). A component
// whose sign disagrees is turned whole. Open components take part when their
// signed volume is a clear fraction of what their area and size allow (a
// bowl, an open hull); a flat or nearly flat sheet has no inside and is left
// as it is.
#include <cstdint>

#include "voxd/mesh.h"

namespace voxd {

struct OrientationRepair {
  // Components connected across manifold edges, counting only those with area.
  std::uint64_t components = 0;
  // Triangles turned round in all (a triangle turned by both steps counts once, or not at all).
  std::uint64_t flipped_triangles = 0;
  // Triangles turned to agree with their component.
  std::uint64_t inconsistent_triangles = 0;
  // Components turned whole because they were inside out.
  std::uint64_t inverted_components = 0;
  // Edges whose two triangles no orientation makes agree (a Moebius strip,
  // or a component folded through itself); left as they are.
  std::uint64_t unorientable_edges = 0;
  // The topology the repair saw (as make_mesh_report counts them), the
  // inconsistent edges as written, before the repair.
  std::uint64_t inconsistent_edges = 0;
  std::uint64_t boundary_edges = 0;
  std::uint64_t nonmanifold_edges = 0;

  bool changed() const { return flipped_triangles > 0; }
  // Closed, manifold and, after the repair, consistently oriented: parity,
  // vote and winding number all agree on what is inside.
  bool closed() const { return boundary_edges == 0 && nonmanifold_edges == 0 && unorientable_edges == 0; }
};

// Turns the triangles of `mesh` (by swapping two corners) as described above
// and says what it did. Vertices are not moved or merged; a mesh with no
// triangles is left alone.
OrientationRepair orient_outward(Mesh& mesh);

}  // namespace voxd
