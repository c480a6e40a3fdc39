#pragma once
// The surface of a job's result as a triangle mesh in model coordinates,
// what GET /v1/jobs/{id}/volume?format=stl|ply|glb serves:
//  - voxel_surface(): the faces between filled and empty voxels, each face
//    two triangles facing out (the page's voxel view). Closed: every edge
//    is in exactly two triangles, once each way, so the enclosed volume is
//    the filled voxels' exactly. Where two voxels meet only along an edge
//    or at a corner, the surface keeps them apart (the solid read as
//    6-connected): the edge's and corner's vertices are split, one copy for
//    each sheet, so no edge is shared by four triangles. Where that would
//    leave one sheet passing such an edge twice, the sheet is joined round
//    the empty voxels at that edge instead (one more pass; in 300 random
//    volumes no second was needed).
//  - zero_level_set(): an sdf's zero level set by naive surface nets
//    (Gibson 1998; the page's web/js/surface_nets.js, the same algorithm):
//    one vertex in every cell of eight samples whose signs differ, at the
//    mean of its edges' zero crossings, one quad around every sample edge
//    whose ends differ in sign. Samples one voxel beyond the grid count as
//    outside, so a part that reaches its grid's border is still closed.
#include <cstdint>

#include "voxd/bit_volume.h"
#include "voxd/dense_volume.h"
#include "voxd/mesh.h"

namespace voxd {

// The number of faces between a filled voxel and an empty one or the grid's
// outside: voxel_surface() makes two triangles of each, to size it first.
std::uint64_t boundary_face_count(const BitVolume& volume);
Mesh voxel_surface(const BitVolume& volume);

// `inside_negative`: the sign convention (false: positive inside);
// `outside`: the value, positive, the samples beyond the grid take (the
// page takes half a voxel in the values' unit).
Mesh zero_level_set(const DenseVolume<float>& sdf, bool inside_negative, float outside);

}  // namespace voxd
