// The signed distance field's band on the CPU and on a CUDA GPU (issue #40),
// the benchmark mesh (1.1M triangles) at N^3, band 3 voxels:
// BM_SdfDevice/<N>/<device> with device 0 = cpu (the machine's threads: pass
// VOXD_THREADS=16 to pin them), 1 = cuda. Both include the solid that signs
// the field and the sign, made on the CPU. Counters for cuda, per run: the
// kernels' time (gpu_kernel_ms), the copies' (gpu_copy_ms) and the slabs.
// Without a GPU the cuda runs stop with the reason (bench/gpu/check.sh runs
// them on one).
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <string>

#include "bench_mesh.h"
#include "device_counters.h"
#include "voxd/compute_device.h"
#include "voxd/voxelize/sdf.h"

namespace voxd::bench {
namespace {

void BM_SdfDevice(benchmark::State& state) {
  const Grid g = benchmark_grid(state.range(0));
  SdfOptions o;
  if (const char* t = std::getenv("VOXD_THREADS")) o.threads = std::atoi(t);
  o.device = state.range(1) == 1 ? ComputeDevice::cuda : ComputeDevice::cpu;
  state.SetLabel(to_string(o.device));
  if (o.device == ComputeDevice::cuda && !cuda_unavailable_reason().empty()) {
    state.SkipWithError(cuda_unavailable_reason().c_str());
    return;
  }
  DeviceRunReport report;
  DeviceCounters counters;
  for (auto _ : state) {
    DenseVolume<float> d = signed_distance_field(benchmark_mesh(), g, o, nullptr, nullptr, &report);
    benchmark::DoNotOptimize(d.values().data());
    counters.add(report);
  }
  counters.set(state);
}
BENCHMARK(BM_SdfDevice)
    ->ArgsProduct({{256, 512}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace voxd::bench
