#include "server/jobs/job_analyses.h"
#include "server/jobs/job_manager.h"
#include "server/jobs/job_store.h"

#include <chrono>
#include <cstring>
#include <map>
#include <memory>
#include <mutex>

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "api/job_params.h"
#include "server/jobs/analyses/analysis_support.h"
#include "voxd/analysis/local_thickness.h"
#include "voxd/analysis/wall_thickness.h"
#include "voxd/encode/rle_slabs.h"
#include "voxd/error.h"

namespace voxd::server {
namespace {

using nlohmann::json;
using api::AnalysisRequest;

// One lock per (scope, key) being computed or written, dropped when nobody
// holds it.
class KeyLocks {
 public:
  std::shared_ptr<KeyLock> get(const std::string& name) {
    std::lock_guard guard(mutex_);
    for (auto it = locks_.begin(); it != locks_.end();) it = it->second.expired() ? locks_.erase(it) : std::next(it);
    std::shared_ptr<KeyLock> lock = locks_[name].lock();
    if (!lock) {
      lock = std::make_shared<KeyLock>();
      locks_[name] = lock;
    }
    return lock;
  }

 private:
  std::mutex mutex_;
  std::map<std::string, std::weak_ptr<KeyLock>> locks_;
};

std::shared_ptr<KeyLock> key_lock(const ArtifactAccess& artifacts, const std::string& key) {
  static KeyLocks locks;
  return locks.get(artifacts.scope + "/" + key);
}

}  // namespace

PngScale radiography_scale(const AnalysisRequest& r, const Grid& g) {
  return r.unit == "model" ? PngScale{g.voxel_size, "model units"} : PngScale{1.0, "voxel"};
}

bool streams_over_slabs(const AnalysisRequest& r) { return job_analysis_kind(r.kind).streams_over_slabs(r); }

std::uint64_t whole_grid_memory(const AnalysisRequest& r, const Grid& grid) {
  return bit_volume_bytes(grid.dims) + estimate_analysis_memory(r, grid);
}

std::string whole_grid_refusal(const AnalysisRequest& r, const Grid& grid, std::uint64_t max_job_memory) {
  // The largest cube whose bits and analysis fit: per-voxel cost from two
  // sizes (the estimate is affine in the voxel count).
  Grid unit;
  unit.dims = {1, 1, 1};
  Grid two = unit;
  two.dims = {1024, 1024, 1024};
  const std::uint64_t fixed = whole_grid_memory(r, unit);
  const double per_voxel = static_cast<double>(whole_grid_memory(r, two) - fixed) / static_cast<double>(two.voxel_count());
  const double largest = max_job_memory > fixed ? static_cast<double>(max_job_memory - fixed) / per_voxel : 0.0;
  const auto largest_voxels = static_cast<std::uint64_t>(largest);
  const auto side = static_cast<std::uint64_t>(std::cbrt(largest));
  const std::string what = job_analysis_kind(r.kind).needs_whole_grid(r);
  return what + " needs the whole grid in memory, about " + std::to_string(whole_grid_memory(r, grid) >> 20) +
         " MiB for this job's " + std::to_string(grid.dims.x) + " x " + std::to_string(grid.dims.y) + " x " +
         std::to_string(grid.dims.z) + " grid; the largest grid it accepts here is " + std::to_string(largest_voxels) +
         " voxels (about " + std::to_string(side) + "^3, per-job memory " + std::to_string(max_job_memory >> 20) +
         " MiB). This job's volume was made slab by slab: radiography, sections and shaded previews (without peel "
         "or thickness colours) and the analysis with thickness=false&skin=false stream over it at any size";
}

bool streams_over_slabs(const AnalysisRequest& r, const api::JobParams& params) {
  const bool shows_distances = job_analysis_kind(r.kind).shows_values(r);
  return streams_over_slabs(r) && !(params.mode->distance_values() && shows_distances);
}

std::uint64_t analysis_memory_on_job(const AnalysisRequest& r, const api::JobParams& params, const Grid& grid,
                                     bool streamed_job, std::uint64_t max_job_memory, std::uint64_t triangles) {
  const std::uint64_t mesh = job_analysis_kind(r.kind).bytes_per_triangle(r) * triangles;
  if (!streamed_job) return estimate_analysis_memory(r, grid) + mesh;
  if (streams_over_slabs(r, params)) return estimate_analysis_memory(r, grid, true) + mesh;
  std::uint64_t whole = whole_grid_memory(r, grid) + mesh;
  if (const std::optional<ValueVolume> type = params.value_type())  // its values are read whole too
    whole += grid.voxel_count() * std::visit([]<typename T>(const DenseVolume<T>&) { return sizeof(T); }, *type);
  if (whole > max_job_memory) throw Error(ErrorCode::limit_exceeded, whole_grid_refusal(r, grid, max_job_memory));
  return whole;
}

std::uint64_t estimate_analysis_memory(const AnalysisRequest& r, const Grid& grid, bool over_slabs) {
  const JobAnalysisKind& kind = job_analysis_kind(r.kind);
  // Over slabs: one replayed slab (of values, or the run reader's batch of
  // layers decoded on every core) and the kind's images; else its bytes a
  // voxel on the whole grid.
  if (over_slabs)
    return kReplaySlabBytes + run_reader_batch_bytes(0) + kind.over_slabs_memory(r, grid) + kImagesAndReports;
  return kind.whole_grid_bytes_per_voxel(r) * grid.voxel_count() + kImagesAndReports;
}

ArtifactAccess artifacts_of(JobManager& jobs, const std::string& id) {
  return {id, [&jobs, id](const std::string& key) { return jobs.load_artifact(id, key); },
          [&jobs, id](const std::string& key, std::string_view bytes) { jobs.save_artifact(id, key, bytes); },
          nullptr,
          [&jobs, id](const std::string& key, std::span<char> out) { return jobs.load_artifact_into(id, key, out); }};
}

// One kept map per measure; the names changed when the report moved from
// local to wall thickness, so a map kept by an older replica is never read
// as the other measure.
const char* thickness_map_key(api::ThicknessMeasure m) {
  return m == api::ThicknessMeasure::wall ? "wall-thickness-map.f32" : "local-thickness-map.f32";
}

JobThicknessMap job_thickness_map(const BitVolume& volume, const ArtifactAccess& artifacts, JobControl* control,
                                  api::ThicknessMeasure measure) {
  if (measure == api::ThicknessMeasure::wall && artifacts.wall_map && artifacts.wall_map->grid().dims == volume.grid().dims)
    return {artifacts.wall_map, {}};
  const char* key = thickness_map_key(measure);
  auto mutex = key_lock(artifacts, key);
  std::unique_lock<KeyLock> lock(*mutex);
  {
    // Read into the map itself where the store can: every byte is read, so
    // its memory is neither cleared nor faulted in before (a miss leaves
    // fresh pages untouched for the computation's own volumes).
    auto map = std::make_shared<DenseVolume<float>>(volume.grid(), DenseVolume<float>::Uninitialized{});
    const std::span<char> bytes(reinterpret_cast<char*>(map->values().data()), map->values().size() * sizeof(float));
    if (artifacts.load_into) {
      if (artifacts.load_into(key, bytes)) return {map, {}};
    } else if (auto kept = artifacts.load(key); kept && kept->size() == bytes.size()) {
      std::memcpy(bytes.data(), kept->data(), bytes.size());
      return {map, {}};
    }
  }
  const auto t0 = std::chrono::steady_clock::now();
  // Made by the computation itself: a map allocated beforehand would sit
  // beside the computation's own volumes at its peak (4 bytes a voxel).
  std::shared_ptr<const DenseVolume<float>> map = std::make_shared<const DenseVolume<float>>(
      measure == api::ThicknessMeasure::wall ? wall_thickness(volume, 0, control) : local_thickness(volume, 0, control));
  spdlog::info("job {}: {} thickness computed in {:.3f} s", artifacts.scope, to_string(measure),
               std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  // Kept from the map's own memory (a copy of 4 bytes a voxel would be the
  // report's largest allocation after the map), while the caller uses it.
  auto save = [save = artifacts.save, key = std::string(key), map] {
    save(key, std::string_view(reinterpret_cast<const char*>(map->values().data()), map->values().size() * sizeof(float)));
  };
  return {map, BackgroundSave(std::move(mutex), std::move(lock), "job " + artifacts.scope + ": " + key, std::move(save))};
}

AnalysisResult job_analysis(const AnalysisRequest& r, const JobSnapshot& job, const JobOutput& output,
                            const ArtifactAccess& artifacts, JobControl* control) {
  // Kept before it returns: the answer's bytes are its own to move.
  AnalysisAnswer answer = job_analysis_answer(r, job, output, artifacts, SIZE_MAX, control);
  return {std::move(*answer.bytes), answer.kept};
}

AnalysisAnswer job_analysis_answer(const AnalysisRequest& r, const JobSnapshot& job, const JobOutput& output,
                                   const ArtifactAccess& artifacts, std::size_t keep_while_sent_from,
                                   JobControl* control) {
  const std::string key = r.artifact_key();
  if (auto kept = artifacts.load(key)) return {std::make_shared<std::string>(std::move(*kept)), true, nullptr};
  auto mutex = key_lock(artifacts, key);
  std::unique_lock<KeyLock> lock(*mutex);
  if (auto kept = artifacts.load(key))  // computed while we waited
    return {std::make_shared<std::string>(std::move(*kept)), true, nullptr};
  // A streamed job's request that streams is answered from its slabs with
  // the bytes the in-memory path gives.
  const JobAnalysisKind& kind = job_analysis_kind(r.kind);
  const AnalysisInput in{r, job, output, artifacts, control};
  auto bytes = std::make_shared<std::string>(output.solid ? kind.compute(in, *output.solid) : kind.over_slabs(in));
  if (bytes->size() < keep_while_sent_from) {
    artifacts.save(key, *bytes);
    return {bytes, false, nullptr};
  }
  auto save = [save = artifacts.save, key, bytes] { save(key, *bytes); };
  return {bytes, false,
          std::make_shared<BackgroundSave>(std::move(mutex), std::move(lock), "job " + artifacts.scope + ": " + key,
                                           std::move(save))};
}

nlohmann::json analyses_status(const std::vector<AnalysisRequest>& requests, const char* state) {
  json out = json::array();
  for (const AnalysisRequest& r : requests)
    out.push_back({{"request", api::to_json(r)}, {"state", state}, {"error", nullptr}});
  return out;
}


JobOutput analysis_output(const AnalysisRequest& r, const JobSnapshot& job, const JobStore& store) {
  JobOutput output;
  if (job.streamed && streams_over_slabs(r, *job.job)) {
    output.rle = store.volume_rle(job.id);
    if (job.has_value_volume()) output.values_rle = store.layer_rle(job.id, "values");
    return output;
  }
  output.solid = store.load_volume(job.id);
  if (job.has_value_volume()) output.values = store.load_layer(job.id, "values");
  return output;
}

}  // namespace voxd::server
