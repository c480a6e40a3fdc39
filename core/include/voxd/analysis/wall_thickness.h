#pragma once
// Wall thickness: at every filled voxel, the distance between the two
// opposite surfaces of the wall it belongs to. This is what a thin-wall
// check in casting, moulding or 3D printing means, and what local thickness
// (voxd/analysis/local_thickness.h, the largest inscribed ball, which is
// small at every convex edge and corner by definition) does not measure.
//
// Definition (a θ-medial axis, after Foskey, Lin & Manocha 2003). A point
// of the solid lies on a wall's medial surface when its two nearest surface
// points lie on surfaces that FACE EACH OTHER: their normals at least
// kWallSeparationDegrees (150°) apart. Between the two faces of a wall
// (plate, shell, tube, rib) they are 180° apart; at a convex edge they are
// 180° minus the edge's dihedral angle apart (a box edge 90°, a chamfer
// 45°, a 60° thread's flanks 120°), so edges, corners and thread teeth have
// no medial point of their own: they are the ends of walls, not walls. The
// wall's thickness at a medial point is the distance between its two
// faces; every voxel of the wall takes it, and the edges and corners take
// the value of the wall they end.
//
// On voxels (wall_thickness.cpp):
//  - an exact feature transform gives each filled voxel its nearest empty
//    voxel; two face-adjacent filled voxels whose nearest empty voxels
//    differ straddle a medial surface when planes fitted to the surface
//    around those empty voxels (5^3 windows) face each other (150°); where a
//    fit cannot be trusted (at a concave edge, where a rib meets a wall, the
//    fitted normal is the corner's bisector) the lattice directions decide;
//  - the thickness is the distance between the two fitted planes, each
//    placed from the window's filled-voxel count, so a wall along the grid
//    axes N voxels thick reads exactly N;
//  - each medial voxel paints its chord (the segment across the wall through
//    it), then its ball (largest first, the painting engine of local
//    thickness, analysis/ball_painting.h) the rest, both only between the
//    wall's two faces and only voxels no deeper than the ball; edges and
//    corners then take the largest wall whose ball, grown by sqrt(3),
//    reaches them between its faces, and the last few their neighbours'.
//
// Error bound (wall_thickness_error_bound()): within one voxel of the
// distance between the faces for walls with parallel or gently curved faces
// at any orientation: the voxelization itself puts a face anywhere within a
// voxel. Exact (the voxel count) for walls along the grid axes. Tested on
// plates (sharp, chamfered, rotated 30° about two axes, three voxel sizes),
// tubes, spherical shells and an L-bracket with a thin fin. So a wall at
// least min_wall + 1 voxel thick is never reported thin. Limits: a round
// bar (no parallel faces) reads up to a few voxels under its diameter off
// its centre when it is under about 30 voxels across; a wall tapering by
// less than a voxel per 5 voxels along the grid is a staircase in the voxel
// model, and reads as the staircase's steps.
//
// Cost: the feature transform (about twice the distance transform's), one
// pass over the voxels for the medial pairs, and the painting. Memory: one
// uint32 per voxel (the feature transform), the float result, a few bits
// per voxel, 16 bytes per medial voxel and per voxel left to the balls'
// sparse phase.
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
