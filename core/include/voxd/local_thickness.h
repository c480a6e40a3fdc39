#pragma once
// Local thickness (Hildebrand & Rüegsegger 1997), as BoneJ and Fiji's "Local
// Thickness" compute it: the thickness at a filled voxel is the diameter of
// the largest ball that fits inside the solid and contains the voxel.
//
// Convention (Fiji's): a ball is centred on a filled voxel centre c with
// radius r(c) = sqrt(d2(c)), d2 the exact squared distance to the nearest
// EMPTY voxel centre (voxd/distance_transform.h); it covers the voxels whose
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
// Method: the distance ridge (the centres whose ball is not contained in the
// ball of a 26-neighbour) carries every maximal ball, so only ridge balls are
// painted. Balls are painted largest first, and each voxel is written once:
// per row, a skip list jumps over voxels already holding a larger value, so
// the cost is the ridge's ball rows plus the voxel count, not the sum of the
// ball volumes. Threads own disjoint z-slabs and paint each ball's discs in
// their slabs.
//
// Known limit (measured, bench/local_thickness_bench.cpp): a 26-neighbour
// ball only contains a ball when the distance grows by a full step along that
// neighbour direction, which on walls tilted to the grid almost never happens,
// so the ridge keeps ~90% of the filled voxels and the cost is about
// (filled voxels) x (rows per ball): 18 s for the 256^3 benchmark torus on 2
// cores, far from interactive at 512^3. Exact but slow on thick parts.
//
// Memory: the float result, the uint32 distance transform (reused for the
// skip lists) and 16 bytes per ridge voxel.
#include <cstdint>
#include <string>
#include <vector>

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

// Throws Error(invalid_argument) when bins < 1.
ThicknessStatistics thickness_statistics(const DenseVolume<float>& thickness, int bins);

// How far a reported thickness can be from the mesh's true wall thickness, in
// voxels, for walls with parallel faces:
//  - the voxelization puts a wall of true thickness T (voxels) into N voxels,
//    N within (T - 1, T + 1) (centre-inside test: a face can fall anywhere
//    within a voxel);
//  - the convention above reports N or N + 1 for N voxels.
// So reported - T lies in (-1, +2) voxels. Curved features add the error of a
// sphere centred on voxel centres (under one voxel for radii of a few voxels).
struct ThicknessErrorBound {
  double below_voxels = 1.0;  // reported >= true - below_voxels
  double above_voxels = 2.0;  // reported <= true + above_voxels
};
ThicknessErrorBound thickness_error_bound();
// The bound as a sentence for reports, in voxels and in model units, e.g.
// "-1 to +2 voxels (-0.1 to +0.2 model units) ...".
std::string thickness_error_statement(double voxel_size);

}  // namespace voxd
