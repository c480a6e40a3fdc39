// Palette voxelization of the benchmark mesh (1.1M triangles). Target
// (issue #6): the 46-element palette under nearest with t = 16 rays per
// column and p = 4 points per voxel and ray, at 256^3, within 2 s on 2
// cores. The other palettes and metrics show what the palette size and the
// admissibility tests cost. Counter: voxels that needed an evaluation
// (neither full nor empty with similarity 255).
#include <benchmark/benchmark.h>

#include "bench_mesh.h"
#include "voxd/grid.h"
#include "voxd/voxelize/palette.h"

namespace voxd::bench {
namespace {

void run(benchmark::State& state, int palette, PaletteMetric metric) {
  const Grid g = benchmark_grid(state.range(0));
  PaletteOptions o;
  o.palette = builtin_palette(palette);
  o.metric = metric;
  o.rays = 16;
  o.points = 4;
  PaletteVolume v;
  for (auto _ : state) {
    v = voxelize_palette(benchmark_mesh(), g, o);
    benchmark::DoNotOptimize(v.element.values().data());
  }
  std::uint64_t partial = 0;
  for (std::size_t i = 0; i < v.element.values().size(); ++i)
    partial += v.element.values()[i] > 1 || v.similarity.values()[i] < 255;
  state.counters["partial_voxels"] = static_cast<double>(partial);
}

void BM_Palette46Nearest(benchmark::State& state) { run(state, 46, PaletteMetric::nearest); }
BENCHMARK(BM_Palette46Nearest)->Arg(128)->Arg(256)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Palette78Nearest(benchmark::State& state) { run(state, 78, PaletteMetric::nearest); }
BENCHMARK(BM_Palette78Nearest)->Arg(256)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Palette2Nearest(benchmark::State& state) { run(state, 2, PaletteMetric::nearest); }
BENCHMARK(BM_Palette2Nearest)->Arg(256)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Palette46Outer(benchmark::State& state) { run(state, 46, PaletteMetric::outer); }
BENCHMARK(BM_Palette46Outer)->Arg(256)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace voxd::bench
