// Signed distance field of the benchmark mesh (the 1.1M-triangle tilted
// torus): the narrow band (3 voxels) at 256^3 and 512^3, and the exact field
// on the whole grid at 128^3, 256^3 and 512^3, its nearest-triangle queries by the
// oriented-box tree (BM_SdfFull) and by Embree's rtcPointQuery
// (BM_SdfFullEmbree). Each includes the solid voxelization that signs it.
// Counters: voxels of the grid.
#include <benchmark/benchmark.h>

#include "bench_mesh.h"
#include "voxd/grid.h"
#include "voxd/detail/sdf_tuning.h"
#include "voxd/voxelize/sdf.h"

namespace voxd::bench {
namespace {

const Mesh& mesh() { return benchmark_mesh(); }
// Room for the band outside the mesh.
Grid grid_at(std::int64_t resolution) { return benchmark_grid(resolution, 3); }

void run(benchmark::State& state, bool full, detail::SdfTuning::Nearest nearest = detail::SdfTuning::Nearest::tree) {
  const Grid g = grid_at(state.range(0));
  SdfOptions o;
  o.band = 3.0;
  o.full = full;
  for (auto _ : state) {
    auto sdf = signed_distance_field(mesh(), g, o, nullptr, detail::SdfTuning{nearest});
    benchmark::DoNotOptimize(sdf.values().data());
  }
  state.counters["voxels"] = static_cast<double>(g.voxel_count());
}

void BM_SdfBand(benchmark::State& state) { run(state, false); }
BENCHMARK(BM_SdfBand)->Arg(256)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_SdfFull(benchmark::State& state) { run(state, true); }
BENCHMARK(BM_SdfFull)->Arg(128)->Arg(256)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_SdfFullEmbree(benchmark::State& state) { run(state, true, detail::SdfTuning::Nearest::embree); }
BENCHMARK(BM_SdfFullEmbree)->Arg(128)->Arg(256)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace voxd::bench
