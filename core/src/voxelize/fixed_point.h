#pragma once
// The engine's grid-aligned fixed point (fixed_point_mesh.h says what a
// coordinate means): 2^-20 voxel, voxel centres on multiples of kFixedOne.
// Plain integers only, for the CPU and the CUDA kernels alike.
#include <cstdint>

#include "voxelize/host_device.h"

namespace voxd::detail {

inline constexpr int kFixedBits = 20;
inline constexpr std::int64_t kFixedOne = std::int64_t{1} << kFixedBits;
// Keeps every product in the scan converter inside __int128 with margin.
inline constexpr std::int64_t kFixedLimit = std::int64_t{1} << 60;

// floor(q / kFixedOne) and ceil(q / kFixedOne) (C++20 >> is arithmetic).
VOXD_HD inline std::int64_t floor_fixed(std::int64_t q) { return q >> kFixedBits; }
VOXD_HD inline std::int64_t ceil_fixed(std::int64_t q) { return -((-q) >> kFixedBits); }

}  // namespace voxd::detail
