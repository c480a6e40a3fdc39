// Mesh ingest speed on a 1.1M-triangle torus: the binary STL decode from
// memory (the format of large uploads), welding its soup, the report, and
// what "inside": "auto" adds to a job: the edge count it chooses from (on
// 1, 2 and all threads; and for a 10,000-triangle job), and orienting the mesh (the winding number's, or
// a closed mesh's that is inside out).
// Run: build/bench/mesh_io_bench --benchmark_min_time=2
#include <benchmark/benchmark.h>

#include "support/test_meshes.h"
#include "voxd/mesh_io/mesh_decode.h"
#include "voxd/edge_topology.h"
#include "voxd/mesh_orientation.h"
#include "voxd/mesh_report.h"
#include "voxd/parallel.h"

namespace {

using namespace voxd;

// 1000 x 550 quads = 1,100,000 triangles.
const std::vector<std::uint8_t>& torus_stl() {
  static const std::vector<std::uint8_t> bytes = test::to_binary_stl(test::make_torus({0, 0, 0}, 40, 10, 1000, 550));
  return bytes;
}

const Mesh& torus_soup() {
  static const Mesh soup = decode_mesh_as(MeshFormat::stl_binary, torus_stl());
  return soup;
}

// The service's small job: 100 x 50 quads = 10,000 triangles, as uploaded.
const Mesh& small_soup() {
  static const Mesh soup =
      decode_mesh_as(MeshFormat::stl_binary, test::to_binary_stl(test::make_torus({0, 0, 0}, 40, 10, 100, 50)));
  return soup;
}

void BM_DecodeBinaryStl(benchmark::State& state) {
  const auto& bytes = torus_stl();
  for (auto _ : state) benchmark::DoNotOptimize(decode_mesh(bytes, "torus.stl"));
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * bytes.size()));
  state.counters["triangles"] = static_cast<double>((bytes.size() - 84) / 50);
}
BENCHMARK(BM_DecodeBinaryStl)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_WeldSoup(benchmark::State& state) {
  const Mesh& soup = torus_soup();
  for (auto _ : state) benchmark::DoNotOptimize(weld_vertices(soup));
}
BENCHMARK(BM_WeldSoup)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_MeshReport(benchmark::State& state) {
  const Mesh& soup = torus_soup();
  for (auto _ : state) benchmark::DoNotOptimize(make_mesh_report(soup));
}
BENCHMARK(BM_MeshReport)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_EdgeTopology(benchmark::State& state) {
  const Mesh& soup = torus_soup();
  const int threads = state.range(0) > 0 ? static_cast<int>(state.range(0)) : default_thread_count();
  for (auto _ : state) benchmark::DoNotOptimize(count_edge_topology(soup, threads));
  state.counters["threads"] = threads;
}
BENCHMARK(BM_EdgeTopology)->Arg(1)->Arg(2)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();

// What every small job pays for "inside": "auto" (issue #39: the small
// jobs' throughput).
void BM_EdgeTopologySmall(benchmark::State& state) {
  const Mesh& soup = small_soup();
  for (auto _ : state) benchmark::DoNotOptimize(count_edge_topology(soup));
}
BENCHMARK(BM_EdgeTopologySmall)->Unit(benchmark::kMicrosecond)->UseRealTime();

void BM_OrientOutward(benchmark::State& state) {
  const Mesh& soup = torus_soup();
  for (auto _ : state) {
    state.PauseTiming();
    Mesh copy = soup;
    state.ResumeTiming();
    benchmark::DoNotOptimize(orient_outward(copy));
  }
}
BENCHMARK(BM_OrientOutward)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
