// Per-stage benchmarks of the engine on the 1.1M-triangle benchmark mesh:
// parse (binary STL from memory), voxelize (parity) at 256^3..2048^3, encode,
// a stored RLE read back as runs, and the streamed report, radiograph and
// preview over those runs.
#include <cstdlib>
#include <map>
#include <span>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "bench_mesh.h"
#include "callgrind_section.h"
#include "schedule_simulation.h"
#include "voxd/analysis/components.h"
#include "voxd/analysis/mass_properties.h"
#include "voxd/analysis/analysis_images.h"
#include "voxd/analysis/preview.h"
#include "voxd/analysis/radiography.h"
#include "voxd/grid.h"
#include "voxd/mesh_io/mesh_decode.h"
#include "voxd/encode/rle_slabs.h"
#include "voxd/encode/slab_writer.h"
#include "voxd/encode/volume_format.h"
#include "voxd/voxelize/runs.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd::bench {
namespace {

const Mesh& mesh() { return benchmark_mesh(); }
Grid grid_at(std::int64_t resolution) { return benchmark_grid(resolution); }

void BM_ParseBinaryStl(benchmark::State& state) {
  const std::vector<std::uint8_t> stl = test::to_binary_stl(mesh());
  for (auto _ : state) {
    Mesh m = decode_mesh(stl, "bench.stl");
    benchmark::DoNotOptimize(m.triangles.data());
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * stl.size()));
  state.counters["triangles"] = static_cast<double>(mesh().triangle_count());
}
BENCHMARK(BM_ParseBinaryStl)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_VoxelizeParity(benchmark::State& state) {
  const Grid g = grid_at(state.range(0));
  for (auto _ : state) {
    BitVolume v = voxelize_parity(mesh(), g, 0, 0, nullptr);
    benchmark::DoNotOptimize(v.data());
  }
  state.counters["voxels"] = static_cast<double>(g.voxel_count());
}
BENCHMARK(BM_VoxelizeParity)->Arg(256)->Arg(512)->Arg(1024)->Arg(2048)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_VoxelizeSurface(benchmark::State& state) {
  const Grid g = grid_at(state.range(0));
  for (auto _ : state) {
    BitVolume v = voxelize_surface(mesh(), g, 0, nullptr);
    benchmark::DoNotOptimize(v.data());
  }
}
BENCHMARK(BM_VoxelizeSurface)->Arg(256)->Arg(1024)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_VoxelizeVote(benchmark::State& state) {
  const Grid g = grid_at(state.range(0));
  for (auto _ : state) {
    BitVolume v = voxelize_vote(mesh(), g, 0, nullptr);
    benchmark::DoNotOptimize(v.data());
  }
}
BENCHMARK(BM_VoxelizeVote)->Arg(1024)->Unit(benchmark::kMillisecond)->UseRealTime();

struct CountingSink final : ByteSink {
  using ByteSink::write;
  std::uint64_t n = 0;
  void write(std::span<const std::uint8_t> b) override { n += b.size(); }
};

// The parity solid straight to its RLE (voxd/voxelize/runs.h): what
// `voxd voxelize -o X.rle` runs after parsing; the dense path is
// BM_VoxelizeParity plus BM_Encode's rle. Second argument 1: the writer's
// preparer encodes each slab on the thread that made it, as the CLI and the
// service do; 0: the writer encodes on the one thread that writes in order.
void BM_VoxelizeRunsToRle(benchmark::State& state) {
  const Grid g = grid_at(state.range(0));
  const bool prepared = state.range(1) != 0;
  VoxelizeOptions options;  // VOXD_THREADS=N: N threads (default: every core)
  if (const char* t = std::getenv("VOXD_THREADS")) options.threads = std::atoi(t);
  const Mesh& m = mesh();
  const CallgrindSection section("BM_VoxelizeRunsToRle/" + std::to_string(state.range(0)) + "/" +
                                 std::to_string(state.range(1)) + "/threads:" + std::to_string(options.threads));
  const ScheduleSimulation simulated(state, options.threads);
  for (auto _ : state) {
    CountingSink sink;
    BitSlabWriter writer(g, VolumeFormat::rle, {}, sink);
    voxelize_runs(
        m, g, options, [&](std::int64_t k0, const RunSlab& runs) { writer.write(k0, runs); }, nullptr, {},
        prepared ? writer.preparer() : RunSlabPreparer());
    writer.finish();
    benchmark::DoNotOptimize(sink.n);
    state.counters["bytes"] = static_cast<double>(sink.n);
  }
  state.SetLabel(prepared ? "encoded where made" : "encoded by the writer");
}
BENCHMARK(BM_VoxelizeRunsToRle)
    ->ArgsProduct({{256, 512, 1024, 2048}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
// And at the size issue #39 asks to scale from 2 to 16 threads (140 MB of RLE).
BENCHMARK(BM_VoxelizeRunsToRle)->Args({8192, 1})->Unit(benchmark::kMillisecond)->UseRealTime();

// The solid's RLE at `resolution`, made once.
const std::vector<std::uint8_t>& stored_rle(std::int64_t resolution) {
  static std::map<std::int64_t, std::vector<std::uint8_t>> stored;
  std::vector<std::uint8_t>& rle = stored[resolution];
  if (rle.empty()) {
    const Grid g = grid_at(resolution);
    VectorSink sink;
    BitSlabWriter writer(g, VolumeFormat::rle, {}, sink);
    voxelize_runs(
        mesh(), g, VoxelizeOptions{}, [&](std::int64_t k0, const RunSlab& runs) { writer.write(k0, runs); }, nullptr,
        {}, writer.preparer());
    writer.finish();
    rle = std::move(sink.data);
  }
  return rle;
}

std::string section_name(const char* bench, const benchmark::State& state) {
  return std::string(bench) + "/res:" + std::to_string(state.range(0)) + "/threads:" + std::to_string(state.range(1));
}

// A stored solid's RLE read back as runs (read_rle_run_slabs), as every
// streamed analysis, radiograph, section and preview of a stored result
// starts: the layers decoded on `threads` threads (second argument) and
// joined in order, from memory, with a consumer that only counts. The RLE
// is the solid's at the first argument, made once.
void BM_ReadRunSlabs(benchmark::State& state) {
  const std::vector<std::uint8_t>& rle = stored_rle(state.range(0));
  const auto threads = static_cast<int>(state.range(1));
  const std::int64_t nz = grid_at(state.range(0)).dims.z;  // bounds of 1.1M triangles: not the reader's work
  std::uint64_t runs = 0;
  const CallgrindSection section(section_name("BM_ReadRunSlabs", state));
  const ScheduleSimulation simulated(state, threads);
  for (auto _ : state) {
    runs = 0;
    read_rle_run_slabs(std::span<const std::uint8_t>(rle), nz,
                       [&](std::int64_t, const RunSlab& slab) { runs += slab.run_count(); }, {}, threads);
    benchmark::DoNotOptimize(runs);
  }
  state.counters["runs"] = static_cast<double>(runs);
  state.counters["rle_MiB"] = static_cast<double>(rle.size()) / (1 << 20);
}
BENCHMARK(BM_ReadRunSlabs)
    ->ArgsProduct({{2048, 4096}, {1, 2, 16}})
    ->ArgNames({"res", "threads"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The streamed report of a stored solid (server/jobs/analyses/
// report_analysis.cpp's over_slabs): its runs read as above, mass
// properties and parts and voids taken slab by slab, on `threads` threads.
void BM_StreamedReport(benchmark::State& state) {
  const std::vector<std::uint8_t>& rle = stored_rle(state.range(0));
  const Grid g = grid_at(state.range(0));
  const auto threads = static_cast<int>(state.range(1));
  std::size_t parts = 0;
  const CallgrindSection section(section_name("BM_StreamedReport", state));
  const ScheduleSimulation simulated(state, threads);
  for (auto _ : state) {
    VoxelMassAccumulator mass(g);
    ComponentLabeller components(g, threads);
    read_rle_run_slabs(
        std::span<const std::uint8_t>(rle), g.dims.z,
        [&](std::int64_t k0, const RunSlab& slab) {
          mass.add(k0, slab, threads);
          components.add(k0, slab);
        },
        {}, threads);
    benchmark::DoNotOptimize(mass.result());
    parts = components.finish().parts.size();
  }
  state.counters["parts"] = static_cast<double>(parts);
}
BENCHMARK(BM_StreamedReport)
    ->ArgsProduct({{1024, 2048, 4096}, {2, 16}})
    ->ArgNames({"res", "threads"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The streamed radiograph along z (radiography_analysis.cpp's over_slabs):
// the stored runs read, each ray's thickness gathered, the largest as a
// 16-bit PNG.
void BM_StreamedRadiograph(benchmark::State& state) {
  const std::vector<std::uint8_t>& rle = stored_rle(state.range(0));
  const Grid g = grid_at(state.range(0));
  const auto threads = static_cast<int>(state.range(1));
  std::size_t bytes = 0;
  const CallgrindSection section(section_name("BM_StreamedRadiograph", state));
  const ScheduleSimulation simulated(state, threads);
  for (auto _ : state) {
    RadiographyAccumulator image(g, 2);
    read_rle_run_slabs(
        std::span<const std::uint8_t>(rle), g.dims.z,
        [&](std::int64_t k0, const RunSlab& slab) { image.add(k0, slab, threads); }, {}, threads);
    ThicknessImage maps = image.take();
    bytes = radiography_png(maps, 2, RadiographyMeasure::max, false, {}, {}).size();
    free_on_every_thread(maps, threads);  // as the service's radiography_analysis.cpp does
  }
  state.counters["png_bytes"] = static_cast<double>(bytes);
}
BENCHMARK(BM_StreamedRadiograph)
    ->ArgsProduct({{1024, 2048}, {2, 16}})
    ->ArgNames({"res", "threads"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The streamed preview from +z at the service's default size (2048 pixels
// a side at most; preview_analysis.cpp's over_slabs): the visible voxels
// from one read of the stored runs, their normals and shades from a second,
// the PNG.
void BM_StreamedPreview(benchmark::State& state) {
  const std::vector<std::uint8_t>& rle = stored_rle(state.range(0));
  const Grid g = grid_at(state.range(0));
  const auto threads = static_cast<int>(state.range(1));
  const View view{2, true};
  constexpr int kMaxSide = 2048;
  std::size_t bytes = 0;
  const CallgrindSection section(section_name("BM_StreamedPreview", state));
  const ScheduleSimulation simulated(state, threads);
  for (auto _ : state) {
    PreviewRenderer preview(g, view, threads, kMaxSide);
    read_rle_run_slabs(
        std::span<const std::uint8_t>(rle), g.dims.z,
        [&](std::int64_t k0, const RunSlab& slab) { preview.find(k0, slab); }, {}, threads);
    read_rle_run_slabs(
        std::span<const std::uint8_t>(rle), g.dims.z,
        [&](std::int64_t k0, const RunSlab& slab) { preview.shade(k0, slab); }, {}, threads);
    bytes = preview_png(preview.take(), g, view, {}, kMaxSide).size();
  }
  state.counters["png_bytes"] = static_cast<double>(bytes);
}
BENCHMARK(BM_StreamedPreview)
    ->ArgsProduct({{1024, 2048}, {2, 16}})
    ->ArgNames({"res", "threads"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_Encode(benchmark::State& state) {
  const Grid g = grid_at(state.range(0));
  const BitVolume v = voxelize_parity(mesh(), g, 0, 0, nullptr);
  const auto format = static_cast<VolumeFormat>(state.range(1));
  for (auto _ : state) {
    CountingSink sink;
    encode_volume(v, format, sink);
    benchmark::DoNotOptimize(sink.n);
    state.counters["bytes"] = static_cast<double>(sink.n);
  }
  state.SetLabel(to_string(format));
}
BENCHMARK(BM_Encode)
    ->Args({1024, static_cast<int>(VolumeFormat::rle)})
    ->Args({512, static_cast<int>(VolumeFormat::binvox)})
    ->Args({1024, static_cast<int>(VolumeFormat::raw)})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace voxd::bench


