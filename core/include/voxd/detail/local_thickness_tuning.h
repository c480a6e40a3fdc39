#pragma once
// Not part of the engine's API: when the local thickness painting changes
// strategy, for the benchmarks and the tests that run every path against a
// brute-force evaluation. Not installed.
#include "voxd/analysis/local_thickness.h"

namespace voxd {
namespace detail {

// When the painting changes strategy. Only the speed depends on these, never
// the result: the tests run every path against a brute-force evaluation. The
// defaults are what the service uses.
struct LocalThicknessTuning {
  std::int64_t sparse_from = -1;         // leftover voxels that start the sparse phase; -1: max(4096, voxels / 256)
  std::uint64_t first_range = 0;         // centres gathered first; 0: max(2^20, voxels / 64); doubles each time
  std::int64_t reach_rebuild_queries = 4096;  // tree walks before the reach bound may be rebuilt
};
}  // namespace detail

DenseVolume<float> local_thickness(const BitVolume& solid, int threads, JobControl* control,
                                   const detail::LocalThicknessTuning& tuning);

}  // namespace voxd
