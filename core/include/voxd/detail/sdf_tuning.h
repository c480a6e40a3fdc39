#pragma once
// Not part of the engine's API: how the distance field finds nearest
// triangles, for the benchmarks and the tests that hold every way to the same
// values. Not installed.
#include "voxd/voxelize/sdf.h"

namespace voxd {
namespace detail {

// Choices that change the speed, never a value: for the benchmarks and the
// tests that hold both ways to the same bits.
struct SdfTuning {
  // Nearest-triangle queries beyond the band (`full`): the oriented-box
  // hierarchy, or Embree's BVH through rtcPointQuery.
  enum class Nearest { tree, embree };
  Nearest nearest = Nearest::tree;
};
}  // namespace detail

DenseVolume<float> signed_distance_field(const Mesh& mesh, const Grid& grid, const SdfOptions& options,
                                         JobControl* control, const detail::SdfTuning& tuning);

}  // namespace voxd
