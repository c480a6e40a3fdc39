#pragma once
// Thickness radiography: for every ray (voxel column) along one grid axis, the
// shortest and longest run of filled voxels it crosses and the number of
// filled voxels on it. Walls are measured where a part is thin (min), where it
// is bulky (max), and how much material a straight beam passes (total), in
// voxels, so the answer is exact for the voxel model; multiply by
// Grid::voxel_size for model units.
#include <cstdint>
#include <span>
#include <vector>

#include "voxd/bit_volume.h"
#include "voxd/run_slab.h"
#include "voxd/uncleared_vector.h"

namespace voxd {

// One pixel per ray, row-major (pixel (c, r) at r * width + c). The two axes
// other than the ray axis, in x, y, z order, are column then row:
//   axis 0 (x): column = j, row = k;  axis 1 (y): column = i, row = k;
//   axis 2 (z): column = i, row = j.
// 0 in all three where the ray crosses no material.
// The maps are cleared on every thread when they are made, not on the one
// that makes them (a gigabyte of maps for a radiograph of 8192^3).
struct ThicknessImage {
  int width = 0;
  int height = 0;
  UnclearedVector<std::uint32_t> min;    // shortest filled run on the ray
  UnclearedVector<std::uint32_t> max;    // longest filled run on the ray
  UnclearedVector<std::uint32_t> total;  // filled voxels on the ray
};

// Frees the three maps, their pages given back on up to `threads` threads
// (free_on_every_thread in voxd/uncleared_vector.h): a gigabyte for a
// radiograph of 8192^3 would otherwise be unmapped by one thread.
void free_on_every_thread(ThicknessImage& image, int threads = 0);

// Image size for a projection of `grid` along `axis`: {width, height}.
struct ImageSize {
  int width = 0;
  int height = 0;
};
ImageSize projected_size(const Grid& grid, int axis);

// Computes the three maps along `axis` (0 = x, 1 = y, 2 = z) on up to
// `threads` threads (0 = all cores). Throws Error(invalid_argument) for another
// axis and Error(limit_exceeded) when the image would not fit an int.
ThicknessImage radiography(const BitVolume& volume, int axis, int threads = 0);

// radiography() of a volume that arrives slab by slab in z order (a streamed
// voxelization, a stored result replayed from its RLE): add() every slab,
// then take(). The maps are exactly radiography()'s. Rays along z cross
// slabs: each keeps the layer where its open run began, so memory is the
// image's three maps, one more map and one layer of bits, whatever nz is.
class RadiographyAccumulator {
 public:
  // Throws like radiography() for a bad axis or an image too large.
  RadiographyAccumulator(const Grid& grid, int axis);
  // Layers [k0, k0 + slab.grid().dims.z), right after the previous slab's.
  // Throws std::logic_error out of order.
  void add(std::int64_t k0, const BitVolume& slab, int threads = 0);
  // The same from the slab's runs (a stored RLE read as runs): the cost is
  // the runs and the voxels where rays' runs begin and end, not the grid's
  // bits. All slabs one way (the seam is kept so); mixing throws
  // std::logic_error.
  void add(std::int64_t k0, const RunSlab& slab, int threads = 0);
  // After the last layer. Throws std::logic_error if layers are missing.
  // What the accumulator kept besides the maps is freed on the last add()'s
  // threads.
  ThicknessImage take();

 private:
  Grid grid_;
  int axis_;
  ThicknessImage image_;
  std::int64_t next_k_ = 0;
  int threads_ = 0;  // the last add()'s
  UnclearedVector<std::uint32_t> run_start_;  // z: the layer the ray's open run began at
  std::vector<std::uint64_t> last_layer_; // z: the previous layer's bits (rows of row words)
  RunSlab last_runs_;                      // z: the same as runs
  enum class Kind { none, bits, runs } kind_ = Kind::none;
  void check_slab(std::int64_t k0, Kind slab);  // next in z order, of the accumulator's kind
};

// Summary of one map over the rays that hit material (zeros are skipped).
struct ThicknessStats {
  std::uint64_t rays = 0;  // pixels with a non-zero value
  std::uint32_t min = 0;   // 0 when rays == 0, like everything below
  std::uint32_t max = 0;
  double mean = 0.0;
  // Nearest-rank percentiles: the smallest value v with at least p% of the
  // rays <= v.
  std::uint32_t p5 = 0;
  std::uint32_t p50 = 0;
  std::uint32_t p95 = 0;
  // `bins` equal-width bins over the integer values [min, max]: value v falls
  // in bin floor((v - min) * bins / (max - min + 1)); bin b starts at
  // min + b * bin_width. Empty when rays == 0.
  double bin_width = 0.0;
  std::vector<std::uint64_t> histogram;
};

// Throws Error(invalid_argument) when bins < 1.
ThicknessStats thickness_stats(std::span<const std::uint32_t> values, int bins = 32);

}  // namespace voxd
