// Slice-function voxelization of the benchmark mesh (1.1M triangles): the
// solid, then a colour per filled voxel. Targets (issue #6): colour ramp at
// 512^3 within 1.5 s, Perlin marble at 512^3 within 3 s on 2 cores. The
// solid alone is measured too, so the colouring's share is visible.
// Counter: filled voxels.
#include <benchmark/benchmark.h>

#include "bench_mesh.h"
#include "voxd/grid.h"
#include "voxd/voxelize/slice_functions.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd::bench {
namespace {

void run(benchmark::State& state, SliceFunction function) {
  const Grid g = benchmark_grid(state.range(0));
  SliceOptions o;
  o.function = function;
  o.axis = {0.2, 0.3, 1.0};
  DenseVolume<Rgba8> c;
  for (auto _ : state) {
    c = voxelize_slice(benchmark_mesh(), g, o);
    benchmark::DoNotOptimize(c.values().data());
  }
  std::uint64_t filled = 0;
  for (const Rgba8& v : c.values()) filled += v.a > 0;
  state.counters["filled_voxels"] = static_cast<double>(filled);
}

void BM_SliceColorRamp(benchmark::State& state) { run(state, SliceFunction::color_ramp); }
BENCHMARK(BM_SliceColorRamp)->Arg(256)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_SliceMarble(benchmark::State& state) { run(state, SliceFunction::marble); }
BENCHMARK(BM_SliceMarble)->Arg(256)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_SliceSolidOnly(benchmark::State& state) {
  const Grid g = benchmark_grid(state.range(0));
  for (auto _ : state) {
    BitVolume solid = voxelize(benchmark_mesh(), g, {VoxelMode::solid, InsideTest::parity, 0});
    benchmark::DoNotOptimize(solid.data());
  }
}
BENCHMARK(BM_SliceSolidOnly)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace voxd::bench
