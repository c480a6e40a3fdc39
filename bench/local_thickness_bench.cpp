// Distance transform and local thickness of the benchmark mesh (a thick
// tilted torus) voxelized at 256^3 and 512^3: the thickness analyses a
// part review runs after voxelizing. Also two machined parts made in code
// (tests/support/test_parts.h: a hex nut and a screw: for local thickness,
// sharp edges and thread crests keep voxels unpainted until the smallest
// balls, its slow case; for wall thickness, the nut's flat plate is a large
// medial sheet) at 512^3, the nut and the torus part at 256^3 and 512^3;
// the thickness on the part of the benchmark torus, and the weld a job
// pays to keep its mesh.
// Counters: filled voxels.
#include <benchmark/benchmark.h>

#include "bench_mesh.h"
#include "support/test_parts.h"
#include "voxd/analysis/distance_transform.h"
#include "voxd/grid.h"
#include "voxd/analysis/local_thickness.h"
#include "voxd/analysis/surface_thickness.h"
#include "voxd/analysis/wall_thickness.h"
#include "voxd/mesh_report.h"
#include "voxd/voxelize/voxelize.h"

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

void BM_WallThickness(benchmark::State& state) {
  const BitVolume v = solid_at(state.range(0));
  for (auto _ : state) {
    auto t = wall_thickness(v);
    benchmark::DoNotOptimize(t.values().data());
  }
  state.counters["filled"] = static_cast<double>(v.count());
}
BENCHMARK(BM_WallThickness)->Arg(256)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();

// The CAD-like parts of tests/support/test_parts.h.
template <bool kWall>
void BM_ThicknessPart(benchmark::State& state, const char* file) {
  const Mesh m = test::part_mesh(file);
  GridRequest r;
  r.resolution = state.range(0);
  r.padding = 1;
  const BitVolume v = voxelize_parity(m, resolve_grid(r, bounds(m)), 0, 0, nullptr);
  for (auto _ : state) {
    auto t = kWall ? wall_thickness(v) : local_thickness(v);
    benchmark::DoNotOptimize(t.values().data());
  }
  state.counters["filled"] = static_cast<double>(v.count());
}
void BM_LocalThicknessPart(benchmark::State& state, const char* file) { BM_ThicknessPart<false>(state, file); }
void BM_WallThicknessPart(benchmark::State& state, const char* file) { BM_ThicknessPart<true>(state, file); }
BENCHMARK_CAPTURE(BM_LocalThicknessPart, hex_nut, "hex_nut.stl")->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_LocalThicknessPart, screw, "screw.stl")->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_WallThicknessPart, hex_nut, "hex_nut.stl")->Arg(256)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_WallThicknessPart, screw, "screw.stl")->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_WallThicknessPart, torus, "torus.stl")->Arg(256)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();

// The thickness on the part (voxd/analysis/surface_thickness.h) of the
// 1.1M-triangle benchmark torus from its wall-thickness map: each welded
// vertex's normal and the voxel under it. Counter: vertices.
void BM_SurfaceThickness(benchmark::State& state) {
  const Mesh welded = weld_vertices(make_benchmark_mesh());
  GridRequest r;
  r.resolution = state.range(0);
  r.padding = 1;
  const BitVolume v = voxelize_parity(welded, resolve_grid(r, bounds(welded)), 0, 0, nullptr);
  const DenseVolume<float> map = wall_thickness(v);
  for (auto _ : state) {
    auto s = surface_thickness(welded, map, 10.0f);
    benchmark::DoNotOptimize(s.thickness.data());
  }
  state.counters["vertices"] = static_cast<double>(welded.vertices.size());
}
BENCHMARK(BM_SurfaceThickness)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();

// What a job pays to keep its mesh (server/jobs/kept_mesh.h): welding the
// 1.1M-triangle torus as an STL soup.
void BM_WeldSoup(benchmark::State& state) {
  const Mesh& m = benchmark_mesh();
  Mesh soup;
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    const auto n = static_cast<std::uint32_t>(soup.vertices.size());
    for (int c = 0; c < 3; ++c) soup.vertices.push_back(m.corner(t, c));
    soup.triangles.push_back({n, n + 1, n + 2});
  }
  for (auto _ : state) {
    auto w = weld_vertices(soup);
    benchmark::DoNotOptimize(w.vertices.data());
  }
  state.counters["triangles"] = static_cast<double>(soup.triangle_count());
}
BENCHMARK(BM_WeldSoup)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace voxd::bench
