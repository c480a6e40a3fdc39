#pragma once
// The distance transform with its progress as a share of a larger stage.
#include <cstdint>

#include "analysis/progress_span.h"
#include "voxd/bit_volume.h"
#include "voxd/dense_volume.h"

namespace voxd::detail {

DenseVolume<std::uint32_t> squared_distance_transform(const BitVolume& solid, int threads,
                                                      const ProgressSpan& progress);

}  // namespace voxd::detail
