// Thickness radiography of the benchmark mesh voxelized into a 1024^3 grid
// (solid, parity), along each axis: x scans words within rows, y and z transpose
// 64x64 bit blocks across rows. Also the statistics over the 1024^2 map and
// the other images of a part review at the same size: the shaded preview
// (render and PNG) and a cross-section PNG.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <string>

#include "bench_mesh.h"
#include "voxd/analysis/analysis_images.h"
#include "voxd/grid.h"
#include "voxd/analysis/preview.h"
#include "voxd/analysis/radiography.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd::bench {
namespace {

const BitVolume& volume() {
  static const BitVolume v = [] {
    const Mesh m = make_benchmark_mesh();
    // An explicit 1024^3 grid centred on the mesh: its longest extent spans
    // 1022 voxels (one voxel of padding each side), the others are padded
    // with empty voxels up to 1024.
    const Aabb b = bounds(m);
    const glm::dvec3 extent = b.extent();
    Grid g;
    g.voxel_size = std::max({extent.x, extent.y, extent.z}) / 1022.0;
    g.dims = glm::i64vec3(1024);
    g.origin = b.center() - 512.0 * g.voxel_size;
    return voxelize_parity(m, g, 0, 0, nullptr);
  }();
  return v;
}

void BM_Radiography(benchmark::State& state) {
  const BitVolume& v = volume();
  const int axis = static_cast<int>(state.range(0));
  for (auto _ : state) {
    ThicknessImage img = radiography(v, axis);
    benchmark::DoNotOptimize(img.total.data());
  }
  const glm::i64vec3 d = v.grid().dims;
  state.counters["voxels"] = static_cast<double>(v.grid().voxel_count());
  state.SetLabel(std::string("axis ") + "xyz"[axis] + ", dims " + std::to_string(d.x) + "x" + std::to_string(d.y) + "x" +
                 std::to_string(d.z));
}
BENCHMARK(BM_Radiography)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ThicknessStats(benchmark::State& state) {
  const ThicknessImage img = radiography(volume(), 2);
  for (auto _ : state) {
    ThicknessStats s = thickness_stats(img.max, 64);
    benchmark::DoNotOptimize(s.mean);
  }
}
BENCHMARK(BM_ThicknessStats)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Preview(benchmark::State& state) {
  const View view{static_cast<int>(state.range(0)), true};
  for (auto _ : state) {
    PreviewImage img = render_preview(volume(), view);
    benchmark::DoNotOptimize(img.shade.data());
  }
  state.SetLabel("view " + to_string(view));
}
BENCHMARK(BM_Preview)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_PreviewPng(benchmark::State& state) {
  for (auto _ : state) {
    auto png = preview_png(volume(), View{2, true}, nullptr);
    benchmark::DoNotOptimize(png.data());
  }
}
BENCHMARK(BM_PreviewPng)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_SectionPng(benchmark::State& state) {
  for (auto _ : state) {
    auto png = section_png(volume(), static_cast<int>(state.range(0)), 512);
    benchmark::DoNotOptimize(png.data());
  }
}
BENCHMARK(BM_SectionPng)->Arg(0)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace voxd::bench
