#pragma once
// Local thickness (Hildebrand & Rüegsegger 1997), as BoneJ and Fiji's "Local
// Thickness" compute it: the thickness at a filled voxel is the diameter of
// the largest ball that fits inside the solid and contains the voxel.
//
// Convention (Fiji's): a ball is centred on a filled voxel centre c with
// radius r(c) = sqrt(d2(c)), d2 the exact squared distance to the nearest
// EMPTY voxel centre (voxd/analysis/distance_transform.h); it covers the voxels whose
// centres v satisfy |v - c|^2 <= d2(c), and the thickness is 2 r. So:
//   thickness(v) = max { 2 sqrt(d2(c)) : c filled, |v - c|^2 <= d2(c) }.
// The result is exactly that maximum (the tests compare it with a brute-force
// evaluation of the formula), in voxels; 0 for empty voxels, >= 2 for filled.
//
// Calibration: a flat wall N voxels thick reports exactly N when N is even and
// N + 1 when N is odd (ball centres sit on voxel centres, and the radius
// reaches the first empty centre, half a voxel past the wall's voxel face).
// A sphere voxelized with radius R voxels reports about 2R at its centre. See
// thickness_error_bound() for what this means against the mesh.
//
// Method. Every filled voxel c is a ball centre. Centres are taken largest
// ball first and each ball paints only the voxels that have no value yet;
// the first ball to reach a voxel is the largest that contains it, so the
// result is the maximum by construction. What makes it fast is stopping early
// and skipping work, never approximating:
//  - a ball inside a 26-neighbour's (larger) ball is skipped, checked only
//    when the ball comes up. On walls along the grid axes that drops nearly
//    every ball off the mid-plane; on tilted walls few (the radius seldom
//    grows a whole step per neighbour), which is why it is not a prefilter;
//  - painting ends when no voxel is left without a value. On thick parts the
//    largest few percent of the balls cover almost everything, so the rest of
//    the centres are never sorted: they are gathered range by range from a
//    histogram of the distance values, only when the painting asks for more;
//  - dense phase: a bit per voxel still to paint plus a count per row, so a
//    ball's rows with nothing left cost one comparison; threads own disjoint
//    z-slabs;
//  - sparse phase (few voxels left: sharp edges, thin tips, the lattice
//    fringe of round walls): the leftovers go into a kd-tree with counts, and
//    a ball is first checked against a lower bound of its distance to the
//    nearest leftover (a distance transform of a 4x coarser grid), so a ball
//    that cannot reach one costs a single lookup, and one that can costs a
//    walk of the subtrees its box reaches.
// Cost: on round, thick parts (the benchmark torus) the largest balls leave
// a few leftovers and the whole map takes about the distance transform's time
// again. Sharp edges and thread crests are the slow case: their voxels are
// only reached by the smallest balls, so the sparse phase walks most of the
// centres (a machined nut at 512^3 takes ~10x the torus's time). Measured in
// docs/benchmarks.md (bench/local_thickness_bench.cpp).
//
// Memory: the float result, the uint32 distance transform, a bit per voxel,
// 16 bytes per centre of the range being painted, and in the sparse phase
// about 20 bytes per leftover voxel (it starts with at most a quarter of the
// grid's voxels left).
#include <cstdint>
#include <string>
#include <vector>

#include "voxd/analysis/thickness_error.h"
#include "voxd/bit_volume.h"
#include "voxd/dense_volume.h"
#include "voxd/progress.h"

namespace voxd {

// `threads` 0 = all cores. `control` may be null; when given, progress goes
// from 0 to 1 and cancellation (Error(cancelled)) is honoured.
DenseVolume<float> local_thickness(const BitVolume& solid, int threads = 0, JobControl* control = nullptr);


// Statistics over the filled voxels (thickness > 0) of a local thickness map.
struct ThicknessStatistics {
  std::uint64_t voxel_count = 0;  // filled voxels
  double mean = 0.0;
  double std_dev = 0.0;  // population standard deviation (divides by voxel_count)
  double min = 0.0;
  double max = 0.0;
  // `bins` equal bins over [min, max]; a value v falls in bin
  // floor((v - min) / (max - min) * bins), the maximum in the last bin. With
  // min == max every voxel is in bin 0. Empty when there is no filled voxel.
  std::vector<std::uint64_t> histogram;
  double bin_width() const { return histogram.empty() ? 0.0 : (max - min) / static_cast<double>(histogram.size()); }
};

// Throws Error(invalid_argument) when bins < 1. `threads` 0 = all cores; the
// result does not depend on it (each z layer is summed alone, and the
// layers' sums are added in order).
ThicknessStatistics thickness_statistics(const DenseVolume<float>& thickness, int bins, int threads = 0);

// How far a reported thickness can be from the mesh's true wall thickness, in
// voxels, for walls with parallel faces:
//  - the voxelization puts a wall of true thickness T (voxels) into N voxels,
//    N within (T - 1, T + 1) (centre-inside test: a face can fall anywhere
//    within a voxel);
//  - the convention above reports N or N + 1 for N voxels.
// So reported - T lies in (-1, +2) voxels (tests: plates, a hollow box, tubes
// of 4 to 9 voxel walls). Curved features add the error of a sphere centred
// on voxel centres (under one voxel for radii of a few voxels). At convex
// edges and corners the definition itself gives less than the wall: the
// ball that spans the wall does not reach into the corner.
ThicknessErrorBound thickness_error_bound();  // -1 to +2 voxels
// The bound as a sentence for reports, in voxels and in model units, e.g.
// "-1 to +2 voxels (-0.1 to +0.2 model units) ...".
std::string thickness_error_statement(double voxel_size);

}  // namespace voxd
