#pragma once
// Wall thickness: at every filled voxel, the distance between the two
// opposite surfaces of the wall it belongs to. This is what a thin-wall
// check in casting, moulding or 3D printing means, and what local thickness
// (voxd/analysis/local_thickness.h, the largest inscribed ball, which is
// small at every convex edge and corner by definition) does not measure.
//
// Definition (a θ-medial axis, after Foskey, Lin & Manocha 2003). A point
// of the solid lies on the wall's medial surface when it has two nearest
// surface points that FACE EACH OTHER: the directions from the point to them
// are at least kWallSeparationDegrees (135°) apart. Between the two faces of
// a wall (plate, shell, tube, rib, a wedge narrower than 45°) the directions
// are 180° apart; at a convex edge they are 180° minus the edge's dihedral
// angle apart (a box edge 90°, a chamfer 45°, a 60° thread crest 120°), so
// edges and corners have no medial point of their own: they are not walls,
// they are the ends of walls. The wall thickness at a medial point is the
// distance between its two surface points; every voxel takes the thickness
// of the largest medial ball containing it (the thickest wall it is part
// of: where a thin rib meets a thick wall, the root belongs to the wall),
// and the voxels no medial ball reaches (the corners of sharp edges, the
// outer parts of thread crests) take the largest value of the nearest
// voxels that have one.
//
// On voxels. The surfaces are where filled voxel centres meet empty ones;
// each filled voxel's nearest empty voxel centre comes from an exact feature
// transform. Two face-adjacent filled voxels p, q whose nearest empty voxels
// f(p), f(q) lie in directions at least 135° apart straddle the medial
// surface; the wall there is |f(p) - f(q)| - 1 voxels (the empty centres lie
// half a voxel beyond each surface on a wall along a grid axis), and p and q
// are centres of balls of squared radius |p - f(p)|^2 and |q - f(q)|^2. A
// filled voxel between two empty ones along an axis is a wall 1 voxel thick.
// The painting is local thickness's own exact engine (analysis/ball_painting.h)
// with these centres and values.
//
// Exactness and error bound (see wall_thickness_error_bound()):
//  - a wall along the grid axes N voxels thick reports exactly N voxels;
//    the voxelization puts a wall of true thickness T into N voxels with N
//    within (T - 1, T + 1), so against the mesh the report is within one
//    voxel;
//  - tilted walls: the nearest empty centres lie between 0 and 1 voxel
//    beyond each surface, so |f(p) - f(q)| - 1 lies within (T - 1, T + 1)
//    as well (tests: plates rotated 30° about two axes, tubes, spherical
//    shells, at several voxel sizes);
//  - every voxel of a wall, including its surface voxels and the corners of
//    its edges, reports that wall's value: thin walls are found at their
//    full extent and nowhere else.
//
// Cost: the feature transform (about twice the distance transform's), one
// pass over the voxels for the medial pairs, and the painting of medial
// balls only (a surface's worth of centres, not a volume's). Memory: one
// uint32 per voxel (the feature transform), the float result, a bit per
// voxel, and 16 bytes per medial voxel.
#include <string>

#include "voxd/bit_volume.h"
#include "voxd/dense_volume.h"
#include "voxd/progress.h"

namespace voxd {

// The smallest angle between the directions to a medial point's two nearest
// surface points for it to be inside a wall rather than at an edge.
inline constexpr double kWallSeparationDegrees = 150.0;

// Wall thickness in voxels for every filled voxel (0 for empty ones).
// `threads` 0 = all cores; `control` may be null, else progress goes from 0
// to 1 and cancellation (Error(cancelled)) is honoured.
DenseVolume<float> wall_thickness(const BitVolume& solid, int threads = 0, JobControl* control = nullptr);

struct WallThicknessErrorBound {
  double below_voxels = 1.0;  // reported > true - below_voxels
  double above_voxels = 1.0;  // reported < true + above_voxels
};
WallThicknessErrorBound wall_thickness_error_bound();
// The bound as a sentence for reports, in voxels and model units.
std::string wall_thickness_error_statement(double voxel_size);

}  // namespace voxd
