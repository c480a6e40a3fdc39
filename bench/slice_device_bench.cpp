// The slice functions on the CPU and on a CUDA GPU (issue #40), the
// benchmark mesh (1.1M triangles) at N^3: BM_SliceDevice/<function>/<N>/<device>
// with device 0 = cpu (--threads of the machine: pass VOXD_THREADS=16 to
// pin it), 1 = cuda. Both include the solid, made on the CPU. Counters for
// cuda: the colouring kernel's time (gpu_kernel_ms, what Liao's "real time"
// is measured by) and the copies (gpu_copy_ms) per run, and the slabs.
// Without a GPU the cuda runs stop with the reason (bench/gpu/check.sh runs
// them on one).
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <string>

#include "bench_mesh.h"
#include "device_counters.h"
#include "voxd/compute_device.h"
#include "voxd/voxelize/slice_functions.h"

namespace voxd::bench {
namespace {

constexpr SliceFunction kFunctions[] = {SliceFunction::single_color, SliceFunction::color_ramp,
                                        SliceFunction::interpolated_colors, SliceFunction::checker,
                                        SliceFunction::wood, SliceFunction::marble,
                                        SliceFunction::rock, SliceFunction::custom};

void BM_SliceDevice(benchmark::State& state) {
  const SliceFunction function = kFunctions[state.range(0)];
  const Grid g = benchmark_grid(state.range(1));
  SliceOptions o;
  o.function = function;
  o.axis = {0.2, 0.3, 1.0};
  o.period = 0.3;
  o.noise_scale = 0.2;
  o.lookup_dims = {4, 4, 4};
  o.lookup_colors.assign(64, {90, 160, 220, 255});
  for (std::size_t i = 0; i < 64; i += 3) o.lookup_colors[i] = {250, 120, 40, 255};
  if (const char* t = std::getenv("VOXD_THREADS")) o.threads = std::atoi(t);
  o.device = state.range(2) == 1 ? ComputeDevice::cuda : ComputeDevice::cpu;
  state.SetLabel(std::string(to_string(function)) + " " + to_string(o.device));
  if (o.device == ComputeDevice::cuda && !cuda_unavailable_reason().empty()) {
    state.SkipWithError(cuda_unavailable_reason().c_str());
    return;
  }
  SliceRunReport report;
  DeviceCounters counters;
  for (auto _ : state) {
    DenseVolume<Rgba8> c = voxelize_slice(benchmark_mesh(), g, o, nullptr, &report);
    benchmark::DoNotOptimize(c.values().data());
    counters.add(report);
  }
  counters.set(state);
}

void functions_sizes_devices(benchmark::internal::Benchmark* b) {
  for (int f = 0; f < 8; ++f)
    for (const int n : {256, 512})
      for (const int device : {0, 1}) b->Args({f, n, device});
}
BENCHMARK(BM_SliceDevice)->Apply(functions_sizes_devices)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace voxd::bench
