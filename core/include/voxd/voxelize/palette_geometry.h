#pragma once
// The exact geometry of a palette element (voxd/voxelize/palette.h): a triangle mesh
// of its boundary and its volume, both in unit-voxel coordinates [0, 1]^3.
// Used to export a palette reconstruction as a surface (palette_export.h)
// and to check the built-in palettes' elements against their documented
// volumes.
//
// Each convex piece is the unit cube clipped by its half-spaces, one at a
// time (convex polyhedron clipping): every face polygon is clipped by the
// plane, and the points left on the plane, ordered by angle around the
// plane's normal, close the cut with a cap face. Points within 1e-12 of a
// plane count as on it, so a half-space through a face or a vertex of the
// piece neither splits it nor leaves a sliver. Zero-area faces and pieces of
// zero volume (a half-space that only touches the piece) are dropped.
#include <array>
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "voxd/voxelize/palette.h"

namespace voxd {

// Triangles are counter-clockwise seen from outside (normals point out).
// Each convex piece of the element is its own closed shell, its vertices
// welded (within 1e-12) only among themselves: the pieces of a union may
// touch or overlap (complement_of's pieces touch along their cuts), and
// shells that share no vertex keep every edge shared by exactly two of one
// shell's triangles. The mesh of an overlapping union therefore has internal
// surfaces; its divergence-theorem volume is the sum of the pieces', not
// element_volume's.
struct ElementMesh {
  std::vector<glm::dvec3> vertices;
  std::vector<std::array<std::uint32_t, 3>> triangles;
};

// The empty element gives an empty mesh. Throws Error(invalid_argument) for
// a half-space with a non-finite normal or offset. A zero normal is the
// whole space (offset >= 0) or nothing (offset < 0).
ElementMesh element_mesh(const PaletteElement& element);

// Volume of the union of the pieces, a share of the unit voxel (0 to 1),
// exact up to rounding. Overlaps are counted once, by inclusion-exclusion
// over the intersections of pieces (the intersection of convex pieces is the
// piece with all their half-spaces); intersections of zero volume end their
// branch, so disjoint or touching pieces (complements: up to kMaxPieces)
// cost one intersection per pair. Throws Error(limit_exceeded) when more
// than kMaxVolumeIntersections intersections of positive volume would be
// needed (many mutually overlapping pieces, 2^n - 1 for n of them: beyond
// about 16), and Error(invalid_argument) as element_mesh.
inline constexpr std::size_t kMaxVolumeIntersections = std::size_t{1} << 16;
double element_volume(const PaletteElement& element);

}  // namespace voxd
