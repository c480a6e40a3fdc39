// Distance transform and local thickness of the benchmark mesh (a thick
// tilted torus) voxelized at 256^3 and 512^3: the wall thickness analysis a
// part review runs after voxelizing. Counters: filled voxels.
#include <benchmark/benchmark.h>

#include "bench_mesh.h"
#include "voxd/distance_transform.h"
#include "voxd/grid.h"
#include "voxd/local_thickness.h"
#include "voxd/voxelize.h"

namespace voxd::bench {
namespace {

BitVolume solid_at(std::int64_t resolution) {
  static const Mesh m = make_benchmark_mesh();
  GridRequest r;
  r.resolution = resolution;
  r.padding = 1;
  return voxelize_parity(m, resolve_grid(r, bounds(m)), 0, 0, nullptr);
}

void BM_DistanceTransform(benchmark::State& state) {
  const BitVolume v = solid_at(state.range(0));
  for (auto _ : state) {
    auto d = squared_distance_transform(v);
    benchmark::DoNotOptimize(d.values().data());
  }
  state.counters["filled"] = static_cast<double>(v.count());
}
BENCHMARK(BM_DistanceTransform)->Arg(256)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_LocalThickness(benchmark::State& state) {
  const BitVolume v = solid_at(state.range(0));
  for (auto _ : state) {
    auto t = local_thickness(v);
    benchmark::DoNotOptimize(t.values().data());
  }
  state.counters["filled"] = static_cast<double>(v.count());
}
BENCHMARK(BM_LocalThickness)->Arg(256)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace voxd::bench
