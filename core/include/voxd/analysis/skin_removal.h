#pragma once
// Progressive skin removal (Patil & Ravi): peeling the part one voxel layer at
// a time, as a casting solidifies from its skin inwards. The peel depth of a
// filled voxel is the layer in which it disappears: 1 for the skin. With
// 6-connected peeling (the paper's) a layer is everything face-adjacent to
// the previous layers or to empty space, so the depth is the city-block (L1)
// distance to the nearest empty voxel. The last voxels to go are the thickest
// region: a casting's hot spot.
#include <cstdint>
#include <vector>

#include "voxd/bit_volume.h"
#include "voxd/analysis/components.h"
#include "voxd/dense_volume.h"
#include "voxd/enum_names.h"

namespace voxd {

// How a peel proceeds:
//  - faces: 6-connected, the paper's; depth = city-block (L1) distance to the
//    nearest empty voxel. Layers follow the grid, so corners and slanted
//    walls peel faster than the part's true thickness suggests.
//  - euclidean: a voxel goes in layer ceil(d), d the Euclidean distance from
//    its centre to the nearest empty voxel centre (voxd/analysis/distance_transform.h),
//    so every layer is one voxel size deeper whatever the wall's direction.
enum class PeelMetric { faces, euclidean };
inline constexpr EnumNames<PeelMetric, 2> kPeelMetricNames{{
    {PeelMetric::faces, "faces"}, {PeelMetric::euclidean, "euclidean"}}};
inline const char* to_string(PeelMetric metric) noexcept { return name_of(kPeelMetricNames, metric); }

// Peel depth of every voxel (0 where empty). Voxels outside the grid count as
// empty. Exact: faces in three separable forward/backward sweeps, euclidean
// from the exact distance transform; multithreaded.
DenseVolume<std::uint16_t> peel_depth(const BitVolume& volume, int threads = 0, PeelMetric metric = PeelMetric::faces);

struct PeelSummary {
  std::vector<std::uint64_t> voxels_per_layer;  // [0] = layer 1 (the skin)
  std::uint32_t max_depth = 0;
  std::vector<VoxelRegion> innermost;  // connected regions peeled last, largest first
};

// `threads` 0 = all cores, here and below; the result does not depend on it.
PeelSummary summarize_peeling(const DenseVolume<std::uint16_t>& depth, int threads = 0);

// The model after `layers` peels: voxels whose depth exceeds `layers`.
BitVolume peeled(const DenseVolume<std::uint16_t>& depth, std::uint32_t layers, int threads = 0);

}  // namespace voxd
