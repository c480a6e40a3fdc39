#pragma once
// The GPU's share of a device benchmark's runs (voxd/compute_device.h's
// report), as counters per run: kernels, copies, slabs.
#include <benchmark/benchmark.h>

#include "voxd/compute_device.h"

namespace voxd::bench {

struct DeviceCounters {
  double kernel_ms = 0.0, copy_ms = 0.0;
  DeviceRunReport last;

  void add(const DeviceRunReport& report) {
    kernel_ms += report.gpu_kernel_ms;
    copy_ms += report.gpu_copy_ms;
    last = report;
  }
  void set(benchmark::State& state) const {
    const double runs = static_cast<double>(state.iterations());
    state.counters["gpu_kernel_ms"] = kernel_ms / runs;
    state.counters["gpu_copy_ms"] = copy_ms / runs;
    state.counters["slabs"] = static_cast<double>(last.slabs);
    state.counters["passes"] = static_cast<double>(last.passes);
  }
};

}  // namespace voxd::bench
