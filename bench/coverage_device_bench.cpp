// Grey coverage on the CPU and on a CUDA GPU (issue #40), the benchmark mesh
// (1.1M triangles) at N^3: BM_CoverageDevice/<sampling>/<N>/<device> with
// sampling 0 = exact (k = 4), 1 = stochastic (k = 4), 2 = uniform (k = 4,
// m = 4), and device 0 = cpu (the machine's threads: pass VOXD_THREADS=16 to
// pin them), 1 = cuda. Counters for cuda, per run: the kernels' time
// (gpu_kernel_ms), the copies' (gpu_copy_ms: the mesh in, the floats out),
// the slabs and the passes. Without a GPU the cuda runs stop with the reason
// (bench/gpu/check.sh runs them on one).
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <string>

#include "bench_mesh.h"
#include "device_counters.h"
#include "voxd/compute_device.h"
#include "voxd/voxelize/coverage.h"

namespace voxd::bench {
namespace {

constexpr CoverageSampling kSamplings[] = {CoverageSampling::exact, CoverageSampling::stochastic,
                                           CoverageSampling::uniform};

void BM_CoverageDevice(benchmark::State& state) {
  const Grid g = benchmark_grid(state.range(1));
  CoverageOptions o;
  o.sampling = kSamplings[state.range(0)];
  o.rays = 4;
  if (const char* t = std::getenv("VOXD_THREADS")) o.threads = std::atoi(t);
  o.device = state.range(2) == 1 ? ComputeDevice::cuda : ComputeDevice::cpu;
  state.SetLabel(std::string(to_string(o.sampling)) + " " + to_string(o.device));
  if (o.device == ComputeDevice::cuda && !cuda_unavailable_reason().empty()) {
    state.SkipWithError(cuda_unavailable_reason().c_str());
    return;
  }
  CoverageRunReport report;
  DeviceCounters counters;
  for (auto _ : state) {
    DenseVolume<float> c = voxelize_coverage(benchmark_mesh(), g, o, nullptr, &report);
    benchmark::DoNotOptimize(c.values().data());
    counters.add(report);
  }
  counters.set(state);
}

void samplings_sizes_devices(benchmark::internal::Benchmark* b) {
  for (int s = 0; s < 3; ++s)
    for (const int n : {256, 512, 1024})
      for (const int device : {0, 1}) b->Args({s, n, device});
}
BENCHMARK(BM_CoverageDevice)->Apply(samplings_sizes_devices)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace voxd::bench
