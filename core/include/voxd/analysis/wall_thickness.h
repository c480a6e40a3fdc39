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
//  - the thickness at a medial voxel is the wall's section through it: the
//    distance between the two fitted planes along their common normal, each
//    plane placed from its window's filled-voxel count (so a wall along the
//    grid axes N voxels thick reads exactly N; between faces that are not
//    parallel, the section at the medial voxel, not at the fits'
//    footpoints). On a curved face the voxels are a staircase whose risers
//    tilt a window's fit, both faces' alike, so they still look parallel:
//    a wall 12 voxels or more across whose fits lean off the chord between
//    its two faces' nearest empty voxels is measured along that chord. Then
//    averaged over the medial voxels of the same wall
//    within 3 voxels, which takes most of the lattice's noise out of the
//    fits and keeps a linear taper's value where it is;
//  - every filled voxel takes the wall of its NEAREST medial voxel (a
//    second feature transform, of the medial voxels), if it lies in that
//    wall: no deeper than the wall's ball and a voxel, between its two
//    faces, and with both faces still there when the wall's chord is moved
//    across to it. The nearest medial point is the foot of the voxel's own
//    cross-section, so a tapering wall reads its section where the voxel
//    is, and a wall's ends and edges take the wall they end;
//  - what that leaves (junctions: a rib's root inside the wall it stands
//    on) is painted by the walls' balls, largest first (the painting engine
//    of local thickness, analysis/ball_painting.h), so the thickest wall a
//    voxel is part of owns it; their edges by the balls grown by sqrt(3),
//    and the last few take their neighbours' values.
//
// Why the voxels and not the triangles: measuring from the exact mesh (rays
// from the medial voxels to its faces) was the other way to place a curved
// wall's faces within a voxel. The fits with the chord reach it (99.9-100%
// of the points of a corpus of curved parts within a voxel of the mesh's
// own ray thickness, docs/benchmarks.md, issue #35), work on the volume
// alone (the engine's callers hand it any BitVolume; a job kept before the
// service kept meshes has none), and cost under 1% more; the mesh is the
// tests' reference instead.
//
// Error bound (wall_thickness_error_bound()): within one voxel of the
// distance between the faces for walls with parallel or gently curved faces
// at any orientation: the voxelization itself puts a face anywhere within a
// voxel. Exact (the voxel count) for walls along the grid axes where their
// faces are flat for two voxels around (nearer an edge, the fits lean: a
// 2-voxel wall beside a 5-voxel cavity reads 2.2). Tested on
// plates (sharp, chamfered, rotated 30° about two axes, three voxel sizes),
// tubes, spherical shells, a cup, a drafted sleeve, a boss on a plate and
// filleted ribs (16 to 60 voxels thick, most turned off the grid, 99.9% of
// the points of their faces within a voxel of the mesh's own ray
// thickness: tests/support/wall_parts.h, bench/wall_accuracy), an L-bracket with a thin fin, and wedges turned
// off the grid, whose region under min_wall ends within a voxel of where
// their section crosses it. So a wall at least min_wall + 1 voxel thick is
// never reported thin, and one with flat faces at least min_wall thick
// neither (kWallReportTolerance). Limits: a round bar (no parallel faces) reads up to
// a few voxels under its diameter off its centre when it is under about 30
// voxels across; at the end faces of a tapering wall (within half its
// thickness of them) a voxel takes the medial surface's ragged edge, up to
// three voxels along the taper; a wall tapering by less than a voxel per 5
// voxels along the grid is a staircase in the voxel model, and reads as the
// staircase's steps; by a fillet at a wall's junction with a rib, the
// wall's face within the fillet's first few degrees reads the section a
// little further into the fillet, up to 5 voxels thick (0.2% of a
// filleted rib's points).
//
// Cost: two feature transforms (each about twice the distance
// transform's), one pass over the voxels for the medial pairs and one to
// give each voxel its wall; the balls only at junctions. Memory: one
// uint32 per voxel (the feature transforms, one after the other in the
// same volume), the float result, a few bits per voxel, and about 64 bytes
// per medial voxel.
#include <string>

#include "voxd/analysis/thickness_error.h"
#include "voxd/bit_volume.h"
#include "voxd/dense_volume.h"
#include "voxd/progress.h"

namespace voxd {

// How far under min_wall (over max_wall) a wall must read, in voxels, for
// the report to call it thin (thick). On flat faces at any orientation a
// wall reads within a tenth of a voxel of its thickness (plates turned 30°
// about two axes: -0.09 to +0.04 voxel), so a wall exactly min_wall thick
// would otherwise fail by the lattice's noise; a quarter voxel is well
// inside the error bound.
inline constexpr double kWallReportTolerance = 0.25;

// The smallest angle between the directions to a medial point's two nearest
// surface points for it to be inside a wall rather than at an edge.
inline constexpr double kWallSeparationDegrees = 150.0;

// Wall thickness in voxels for every filled voxel (0 for empty ones).
// `threads` 0 = all cores; `control` may be null, else progress goes from 0
// to 1 and cancellation (Error(cancelled)) is honoured.
DenseVolume<float> wall_thickness(const BitVolume& solid, int threads = 0, JobControl* control = nullptr);

ThicknessErrorBound wall_thickness_error_bound();  // -1 to +1 voxels
// The bound as a sentence for reports, in voxels and model units.
std::string wall_thickness_error_statement(double voxel_size);

}  // namespace voxd
