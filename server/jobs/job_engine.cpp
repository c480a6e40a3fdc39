#include "server/jobs/job_engine.h"

#include <algorithm>
#include <cmath>
#include <random>

#include <spdlog/spdlog.h>

#include "api/error_table.h"
#include "server/jobs/job_analyses.h"
#include "server/jobs/job_record.h"
#include "server/jobs/job_store.h"
#include "server/log_safe.h"

namespace voxd::server {

using Clock = std::chrono::system_clock;

std::string new_job_id() {
  thread_local std::mt19937_64 rng{std::random_device{}() ^ (static_cast<std::uint64_t>(std::random_device{}()) << 32)};
  static constexpr char kHex[] = "0123456789abcdef";
  std::string id(32, '0');
  for (int half = 0; half < 2; ++half) {
    std::uint64_t r = rng();
    for (int i = 0; i < 16; ++i, r >>= 4) id[static_cast<std::size_t>(half * 16 + i)] = kHex[r & 15];
  }
  return id;
}

std::string format_now() { return format_time(Clock::now()); }

JobFailure interrupted(const char* was) {
  return {"interrupted", "Interrupted by a restart",
          std::string("the job was ") + was + " when the service stopped; submit it again"};
}

JobFailure failure_of(const Error& e) {
  const api::ErrorKind& kind = api::error_kind(e.code());
  return JobFailure{kind.slug, "The job failed", kind.client_message ? e.what() : "the job failed unexpectedly; it was logged"};
}

JobEngine::JobEngine(JobManagerConfig c)
    : config(std::move(c)),
      local_queue(std::make_shared<InProcessJobQueue>(config.queue_size)),
      events(config.on_state_change),
      budget(config.memory_budget ? config.memory_budget : available_memory() / 10 * 6) {}

void JobEngine::announce(const JobSnapshot& s) {
  events.announce(s);
  note_change();
}

void JobEngine::note_change() {
  ++changes;
  changed_cv.notify_all();
}

JobSnapshot JobEngine::snapshot_of(const Job& job) const {
  JobSnapshot s = job.snap;
  if (s.state == JobState::running) {
    s.progress = job.control.progress();
    s.stage = job.control.stage();
  }
  return s;
}

void JobEngine::forget_running(const std::string& id) {
  std::lock_guard lock(mutex);
  jobs.erase(id);
}

void JobEngine::warn_backend(const std::exception& e) {
  backend_ok = false;
  const std::int64_t now = std::chrono::duration_cast<std::chrono::seconds>(Clock::now().time_since_epoch()).count();
  std::int64_t last = backend_warned_at_.load();
  if (now - last >= 10 && backend_warned_at_.compare_exchange_strong(last, now))
    spdlog::warn("shared backend: {} (retrying)", e.what());
}

JobLimits JobEngine::job_limits(bool stored) const {
  JobLimits limits = config.limits;
  limits.stream_above_bytes = stored ? std::min(limits.stream_above_bytes, config.max_job_memory) : 0;
  // The store takes slabs and runs; a volume made in memory is kept whole
  // (cached, analysed, answered from), so a job of bits is made as runs
  // only when it streams (JobOutputKind's defaults).
  limits.stream_slab_bytes = std::min(limits.stream_slab_bytes, config.max_job_memory / 4);
  limits.welds_mesh = stored;  // it keeps its mesh (kept_mesh.h)
  return limits;
}

std::uint64_t JobEngine::analyses_memory(const api::JobParams& params, const PreparedVoxelJob& prepared) const {
  std::uint64_t peak = 0;
  for (const api::AnalysisRequest& r : params.analyses) {
    try {
      peak = std::max(peak, analysis_memory_on_job(r, params, prepared.grid, prepared.streamed, config.max_job_memory,
                                                      prepared.triangles));
    } catch (const Error& e) {
      throw Error(e.code(), std::string("analyses: ") + e.what());
    }
  }
  return peak;
}

void JobEngine::cache_put(const std::string& id, const JobOutput& output) {
  if (!output.solid) return;  // streamed: kept on disk only
  if (output.values) cache.put(VolumeCache::layer_key(id, "values"), output.values, byte_size(*output.values));
  for (const auto& [name, layer] : output.layers) cache.put(VolumeCache::layer_key(id, name), layer, byte_size(*layer));
  cache.put(id, output.solid, output.solid->byte_size());
}

nlohmann::json JobEngine::prepare_analyses(Job& job, JobStore& store, const std::vector<api::AnalysisRequest>& requests,
                                           const VoxelJobResult& r, const JobOutput& output) {
  nlohmann::json status = analyses_status(requests, "pending");
  if (requests.empty()) return status;
  JobSnapshot view;
  {
    std::lock_guard lock(mutex);
    view = job.snap;
  }
  view.mesh = r.report;
  view.mesh_mass = r.mesh_mass;
  view.inside = r.inside;
  view.warnings = r.warnings;
  view.values = r.volumes.values_info;
  const std::string id = view.id;
  const ArtifactAccess artifacts{
      id, [&store, id](const std::string& key) { return store.load_artifact(id, key); },
      [&store, &job, id](const std::string& key, std::string_view bytes) {
        std::lock_guard guard(job.store_mutex);
        if (job.removed) return;
        try {
          store.save_artifact(id, key, bytes);
        } catch (const std::exception& e) {
          spdlog::warn("job {}: cannot keep artifact {}: {}", id, key, e.what());
        }
      },
      nullptr,
      [&store, id](const std::string& key, std::span<char> out) { return store.load_artifact_into(id, key, out); }};
  // Each entry is shown as soon as it is ready (or failed), not at the end.
  auto publish = [&] {
    std::lock_guard lock(mutex);
    job.snap.analyses = status;
    note_change();
  };
  for (std::size_t i = 0; i < requests.size(); ++i) {
    const double n = static_cast<double>(requests.size());
    job.control.set_span(0.5 + 0.5 * static_cast<double>(i) / n, 0.5 + 0.5 * static_cast<double>(i + 1) / n);
    job.control.set_progress(0.0);
    job.control.set_stage(std::string("analysis: ") + to_string(requests[i].kind));
    try {
      // A streamed job's request that needs the grid whole reads it back.
      const bool whole = !output.solid && !streams_over_slabs(requests[i], *view.job);
      job_analysis(requests[i], view, whole ? analysis_output(requests[i], view, store) : output, artifacts, &job.control);
      status[i]["state"] = "ready";
    } catch (const AnalysisRejected& e) {
      status[i]["state"] = "failed";
      status[i]["error"] = e.what();
    } catch (const Error& e) {
      if (e.code() == ErrorCode::cancelled) throw;
      status[i]["state"] = "failed";
      status[i]["error"] = e.what();
    } catch (const std::exception& e) {
      // One analysis going wrong costs only its own entry, not the volume.
      spdlog::error("job {}: analysis {} failed: {}", id, requests[i].artifact_key(), log_safe(e.what()));
      status[i]["state"] = "failed";
      status[i]["error"] = "the analysis failed unexpectedly; it was logged";
    }
    publish();
  }
  job.control.set_span(0.0, 1.0);
  return status;
}

int JobEngine::retry_after(std::size_t waiting) const {
  const double seconds =
      recent_job_seconds * static_cast<double>(waiting + 1) / static_cast<double>(std::max<std::size_t>(1, worker_count));
  return std::clamp(static_cast<int>(std::ceil(seconds)), 1, 3600);
}

QueueFull JobEngine::queue_full(std::size_t waiting) const {
  return QueueFull("the job queue is full (" + std::to_string(config.queue_size) + " jobs waiting); retry later",
                   retry_after(waiting));
}

void JobEngine::record_success(JobSnapshot& s, const VoxelJobResult& r, std::optional<nlohmann::json> analyses_done) {
  if (analyses_done) s.analyses = std::move(*analyses_done);
  s.state = JobState::succeeded;
  // With the state, in one step: an event stream reading between the two
  // would send an end with no finished_at.
  s.finished_at = format_now();
  s.progress = 1.0;
  s.mesh = r.report;
  s.mesh_mass = r.mesh_mass;
  for (auto& t : r.timings.stages)
    if (std::none_of(s.timings.begin(), s.timings.end(), [&](const auto& x) { return x.first == t.first; }))
      s.timings.push_back(t);
  s.filled_voxels = r.filled;
  s.inside = r.inside;
  s.warnings = r.warnings;
  s.values = r.volumes.values_info.is_null() ? nlohmann::json(nullptr) : r.volumes.values_info;
}

}  // namespace voxd::server
