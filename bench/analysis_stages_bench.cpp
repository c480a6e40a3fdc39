// The analysis report's stages one at a time (issue #39's breakdown): mass
// properties, parts and voids, the skin's peel depths, wall thickness (with
// its phases, timed from its progress reports), the thickness regions and
// statistics the verdict reads, and a preview painted by thickness. On the
// benchmark torus (1.1M triangles, bench_mesh.h) and a CAD part (the hex nut
// of tests/support/test_parts.h), at 256^3 and 512^3.
//   ./build/bench/analysis_stages_bench --benchmark_filter='torus/res:512/threads:(1|2)/'
// Args: resolution, threads (1 to 16; run more threads than cores only to
// see the cost of the split). The thresholds are a third and
// two thirds of the way from the thinnest wall to the mean, so every region
// search has work to do.
#include <algorithm>
#include <chrono>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "bench_mesh.h"
#include "callgrind_section.h"
#include "schedule_simulation.h"
#include "support/test_parts.h"
#include "voxd/analysis/analysis.h"
#include "voxd/analysis/analysis_images.h"
#include "voxd/analysis/components.h"
#include "voxd/analysis/mass_properties.h"
#include "voxd/analysis/skin_removal.h"
#include "voxd/analysis/thickness_regions.h"
#include "voxd/analysis/wall_thickness.h"
#include "voxd/detail/nearest_empty.h"
#include "voxd/grid.h"
#include "voxd/progress.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd::bench {
namespace {

const Mesh& mesh_named(const std::string& name) {
  static std::map<std::string, Mesh> meshes;
  auto it = meshes.find(name);
  if (it == meshes.end()) it = meshes.emplace(name, name == "torus" ? make_benchmark_mesh() : test::part_mesh(name)).first;
  return it->second;
}

const BitVolume& solid(const std::string& name, std::int64_t resolution) {
  static std::map<std::pair<std::string, std::int64_t>, std::unique_ptr<BitVolume>> cache;
  auto& slot = cache[{name, resolution}];
  if (!slot) {
    const Mesh& m = mesh_named(name);
    GridRequest r;
    r.resolution = resolution;
    r.padding = 2;
    slot = std::make_unique<BitVolume>(voxelize_parity(m, resolve_grid(r, bounds(m)), 0, 0, nullptr));
  }
  return *slot;
}

const DenseVolume<float>& thickness(const std::string& name, std::int64_t resolution) {
  static std::map<std::pair<std::string, std::int64_t>, std::unique_ptr<DenseVolume<float>>> cache;
  auto& slot = cache[{name, resolution}];
  if (!slot) slot = std::make_unique<DenseVolume<float>>(wall_thickness(solid(name, resolution)));
  return *slot;
}

int threads_of(const benchmark::State& state) { return static_cast<int>(state.range(1)); }

// The timed loop, also what bench/serial_fraction.sh counts, as STAGE/PART/res:R/threads:T.
CallgrindSection counted(const benchmark::State& state, const char* stage, const char* name) {
  return CallgrindSection(std::string(stage) + "/" + name + "/res:" + std::to_string(state.range(0)) +
                          "/threads:" + std::to_string(threads_of(state)));
}

void counters(benchmark::State& state, const BitVolume& v) {
  state.counters["filled"] = static_cast<double>(v.count());
  state.counters["threads"] = static_cast<double>(threads_of(state));
}

void BM_Mass(benchmark::State& state, const char* name) {
  const BitVolume& v = solid(name, state.range(0));
  const CallgrindSection section = counted(state, "BM_Mass", name);
  const ScheduleSimulation simulated(state, threads_of(state));
  for (auto _ : state) benchmark::DoNotOptimize(voxel_mass_properties(v, threads_of(state)));
  counters(state, v);
}

void BM_PartsAndVoids(benchmark::State& state, const char* name) {
  const BitVolume& v = solid(name, state.range(0));
  const CallgrindSection section = counted(state, "BM_PartsAndVoids", name);
  const ScheduleSimulation simulated(state, threads_of(state));
  for (auto _ : state) benchmark::DoNotOptimize(find_components(v, threads_of(state)));
  counters(state, v);
}

void BM_Skin(benchmark::State& state, const char* name) {
  const BitVolume& v = solid(name, state.range(0));
  const CallgrindSection section = counted(state, "BM_Skin", name);
  const ScheduleSimulation simulated(state, threads_of(state));
  for (auto _ : state)
    benchmark::DoNotOptimize(summarize_peeling(peel_depth(v, threads_of(state), PeelMetric::faces), threads_of(state)));
  counters(state, v);
}

// Records when the progress first reached each phase boundary of
// wall_thickness() (wall_thickness.cpp: 0.3, 0.45, 0.65, 0.75, 0.85, 0.95).
class PhaseClock final : public HostInterrupter {
 public:
  static constexpr double kEnds[] = {0.3, 0.45, 0.65, 0.75, 0.85, 1.0};
  static constexpr const char* kNames[] = {"nearest_empty_ms", "medial_ms", "nearest_medial_ms",
                                           "paint_walls_ms", "paint_balls_ms", "edges_ms"};
  bool interrupted() override { return false; }
  void progressed(double fraction) override {
    const auto now = std::chrono::steady_clock::now();
    std::lock_guard lock(mutex_);
    for (std::size_t p = 0; p < std::size(kEnds); ++p)
      if (fraction >= kEnds[p] - 1e-9 && !reached_[p]) reached_[p] = now;
  }
  void start() { start_ = std::chrono::steady_clock::now(); }
  // Milliseconds of each phase; a phase with no report is folded into the next.
  std::vector<double> phases(std::chrono::steady_clock::time_point end) const {
    std::vector<double> ms;
    auto from = start_;
    for (std::size_t p = 0; p < std::size(kEnds); ++p) {
      const auto to = p + 1 == std::size(kEnds) ? end : reached_[p].value_or(from);
      ms.push_back(std::chrono::duration<double, std::milli>(std::max(to, from) - from).count());
      from = std::max(to, from);
    }
    return ms;
  }

 private:
  std::mutex mutex_;
  std::chrono::steady_clock::time_point start_;
  std::optional<std::chrono::steady_clock::time_point> reached_[std::size(kEnds)];
};

void BM_WallThickness(benchmark::State& state, const char* name) {
  const BitVolume& v = solid(name, state.range(0));
  std::vector<double> sums(std::size(PhaseClock::kEnds), 0.0);
  const CallgrindSection section = counted(state, "BM_WallThickness", name);
  const ScheduleSimulation simulated(state, threads_of(state));
  for (auto _ : state) {
    PhaseClock clock;
    JobControl control(&clock);
    clock.start();
    const DenseVolume<float> t = wall_thickness(v, threads_of(state), &control);
    const std::vector<double> ms = clock.phases(std::chrono::steady_clock::now());
    for (std::size_t p = 0; p < ms.size(); ++p) sums[p] += ms[p];
    benchmark::DoNotOptimize(t.values().data());
  }
  counters(state, v);
  for (std::size_t p = 0; p < sums.size(); ++p)
    state.counters[PhaseClock::kNames[p]] = sums[p] / static_cast<double>(state.iterations());
}

// Wall thickness's first phase on its own: the feature transform (the
// nearest empty voxel of every voxel), which its third phase repeats for
// the nearest medial voxel.
void BM_NearestEmpty(benchmark::State& state, const char* name) {
  const BitVolume& v = solid(name, state.range(0));
  const CallgrindSection section = counted(state, "BM_NearestEmpty", name);
  const ScheduleSimulation simulated(state, threads_of(state));
  for (auto _ : state) benchmark::DoNotOptimize(detail::nearest_empty_voxels(v, threads_of(state)).values().data());
  counters(state, v);
}

// What the report does with the thickness map: statistics, and thin, thick
// and near regions at both thresholds (analysis.cpp).
void BM_ThicknessRegions(benchmark::State& state, const char* name) {
  const BitVolume& v = solid(name, state.range(0));
  const DenseVolume<float>& map = thickness(name, state.range(0));
  AnalysisOptions options;
  options.cleanup.reset();
  options.skin = false;
  options.thickness_map = &map;
  options.threads = threads_of(state);
  const ThicknessStatistics stats = thickness_statistics(map, 32);
  options.min_wall_voxels = stats.min + (stats.mean - stats.min) / 3;
  options.max_wall_voxels = stats.min + 2 * (stats.mean - stats.min) / 3;
  std::size_t regions = 0;
  const CallgrindSection section = counted(state, "BM_ThicknessRegions", name);
  const ScheduleSimulation simulated(state, threads_of(state));
  for (auto _ : state) {
    // Mass and parts are timed above; here they are a small share.
    const AnalysisReport report = analyze_volume(v, options);
    regions = report.thickness->thin_regions.size() + report.thickness->thick_regions.size() +
              report.thickness->near_min_wall.size() + report.thickness->near_max_wall.size();
  }
  counters(state, v);
  state.counters["regions"] = static_cast<double>(regions);
}

void BM_ThicknessPreview(benchmark::State& state, const char* name) {
  const BitVolume& v = solid(name, state.range(0));
  const DenseVolume<float>& map = thickness(name, state.range(0));
  std::size_t bytes = 0;
  const CallgrindSection section = counted(state, "BM_ThicknessPreview", name);
  const ScheduleSimulation simulated(state, threads_of(state));
  for (auto _ : state) bytes = preview_png(v, View{2, true}, &map, {}, threads_of(state)).size();
  counters(state, v);
  state.counters["png_bytes"] = static_cast<double>(bytes);
}

void stage_args(benchmark::internal::Benchmark* b) {
  for (std::int64_t resolution : {256, 512})
    for (std::int64_t threads : {1, 2, 4, 8, 16}) b->Args({resolution, threads});
  b->ArgNames({"res", "threads"})->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1)->Repetitions(3);
}

#define VOXD_STAGE(fn)                               \
  BENCHMARK_CAPTURE(fn, torus, "torus")->Apply(stage_args); \
  BENCHMARK_CAPTURE(fn, hex_nut, "hex_nut.stl")->Apply(stage_args)

VOXD_STAGE(BM_Mass);
VOXD_STAGE(BM_PartsAndVoids);
VOXD_STAGE(BM_Skin);
VOXD_STAGE(BM_NearestEmpty);
VOXD_STAGE(BM_WallThickness);
VOXD_STAGE(BM_ThicknessRegions);
VOXD_STAGE(BM_ThicknessPreview);

}  // namespace
}  // namespace voxd::bench
