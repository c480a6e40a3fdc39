#pragma once
// Thickness on the part itself, as Magics and Netfabb show it: each vertex
// of the mesh takes the wall it bounds, read from a thickness map (voxels;
// the wall thickness, voxd/analysis/wall_thickness.h) at the filled voxel
// under it: the voxel half a voxel inward along the vertex's normal, else
// the filled voxel nearest the vertex within a voxel (a vertex on a convex
// edge, whose normal leans out of the part). A vertex with no filled voxel
// that near bounds a feature thinner than the voxels resolve: it reads 0.
//
// The map's surface voxels carry the wall's thickness within its error
// bound, so a vertex reads within about a voxel of the ray thickness at it
// away from sharp edges (tests/core/surface_thickness_test.cpp); at an edge
// it takes the wall the edge ends.
#include <cstdint>
#include <optional>
#include <vector>

#include <glm/vec3.hpp>

#include "voxd/analysis/thickness_regions.h"
#include "voxd/dense_volume.h"
#include "voxd/mesh.h"

namespace voxd {

// Unit normals of a welded mesh's vertices, each the area-weighted mean of
// its triangles' (outward for an outward-oriented mesh); (0, 0, 0) for a
// vertex of zero-area triangles only.
std::vector<glm::vec3> vertex_normals(const Mesh& mesh);

struct SurfaceThickness {
  // Per vertex, in voxels: the map under it, 0 where no filled voxel lies
  // within a voxel of it.
  std::vector<float> thickness;
  // Per vertex, with a thin threshold: 1 + the index of its thin region in
  // `thin_regions` (find_thickness_regions' list), 0 for none. Else empty.
  std::vector<std::uint32_t> thin_region;
  std::vector<ThicknessRegion> thin_regions;
  std::uint64_t unresolved = 0;  // vertices that read 0
};

// `mesh`: welded (weld_vertices), in the map's frame (the grid's model
// coordinates). `thin_below_voxels`: the report's thin threshold
// (min_wall - kWallReportTolerance, in voxels) for the region ids, with
// its minimum region size.
SurfaceThickness surface_thickness(const Mesh& mesh, const DenseVolume<float>& map,
                                   std::optional<float> thin_below_voxels = std::nullopt,
                                   std::uint64_t min_region_voxels = 1);

}  // namespace voxd
