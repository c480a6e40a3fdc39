#pragma once
// Whether a mesh is closed, counted fast enough to ask of every job: the
// edges of its triangles grouped by their two end positions (bit-identical
// positions are one vertex, as weld_vertices and the mesh report take
// them), without welding. Each edge is keyed by a 63-bit hash of its two
// positions and the direction it is traversed in, the keys are bucketed by
// their top bits and each bucket sorted, all on `threads` threads. Two
// different edges share a hash with probability about n^2 / 2^64 (one in a
// million for 3 million edges), which would count two boundary edges as one
// manifold edge: a price the inside test's choice can pay, and the mesh
// report, which welds, does not.
#include <cstdint>

#include "voxd/mesh.h"

namespace voxd {

struct EdgeTopology {
  std::uint64_t edges = 0;               // distinct edges of the triangles with three distinct corners
  std::uint64_t boundary_edges = 0;      // used by one triangle
  std::uint64_t nonmanifold_edges = 0;   // used by more than two
  std::uint64_t inconsistent_edges = 0;  // two triangles traversing it the same way
  // Six times the signed volume (divergence theorem, about the first
  // vertex): negative for a closed mesh written inside out.
  double six_volume = 0.0;
  bool closed() const { return boundary_edges == 0 && nonmanifold_edges == 0; }
};

// Triangles with two corners at one position take no part, as in the mesh
// report. `threads` 0 = all cores.
EdgeTopology count_edge_topology(const Mesh& mesh, int threads = 0);

// The same counts, exactly (no hash), from weld_vertices(mesh): the edges
// are grouped by a counting sort on their smaller vertex, each in its
// vertex's short bucket, so the pass is two linear sweeps and tiny sorts,
// on one thread. A caller that welds anyway (a job that keeps its mesh, the
// mesh report) pays this instead of the hashing. The volume is summed about
// the same point and in the same order as count_edge_topology's.
EdgeTopology edge_topology_of_welded(const Mesh& welded);

}  // namespace voxd
