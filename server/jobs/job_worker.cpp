// The worker: takes the next job from its backend (or the in-process
// queue), records it running, and runs it: the volumes made (slab by slab
// into the store, as runs, or in memory), stored, analysed, and its end
// handed back to its backend to record.
#include <spdlog/spdlog.h>

#include "api/error_table.h"
#include "server/jobs/job_backend.h"
#include "server/jobs/job_engine.h"
#include "server/jobs/job_store.h"
#include "server/jobs/kept_mesh.h"
#include "server/log_safe.h"
#include "voxd/encode/slab_writer.h"
#include "voxd/mesh_report.h"

namespace voxd::server {

std::shared_ptr<const Mesh> keep_job_mesh(const JobStore& store, const std::string& id, const PreparedVoxelJob& prepared) {
  auto welded = prepared.welded ? prepared.welded : std::make_shared<const Mesh>(weld_vertices(prepared.mesh));
  store.save_artifact(id, kKeptMeshKey, encode_kept_mesh(*welded, prepared.rotation));
  return welded;
}

void JobEngine::work(JobBackend& backend) {
  for (;;) {
    std::shared_ptr<Job> job;
    PreparedVoxelJob prepared;
    const JobBackend::Next next = backend.next(job, prepared);
    if (next == JobBackend::Next::stopped) return;  // the service stops
    if (next == JobBackend::Next::none) continue;
    JobBackend& home = *job->backend;
    bool running = false;
    try {
      running = mark_running(*job);
    } catch (const BackendUnavailable& e) {
      warn_backend(e);
    }
    if (!running) {  // cancelled meanwhile (or the backend went away: the lease runs out)
      job->memory.release();
      home.drop_taken(*job);
      continue;
    }
    deliver();
    const std::string id = job->snap.id;
    try {
      if (home.split(*job, prepared)) continue;
      run(*job, std::move(prepared));
    } catch (const std::exception& e) {
      // run() records every failure of the job itself; this is the
      // bookkeeping after it failing (the backend gone mid-way): the
      // worker lives on, and a shared job's lease lapses.
      spdlog::error("job {}: {}", id, log_safe(e.what()));
      home.abandon(id);
    }
  }
}

std::shared_ptr<Job> JobEngine::take_local(const std::string& id, PreparedVoxelJob& prepared) {
  std::lock_guard lock(mutex);
  auto it = jobs.find(id);
  if (it == jobs.end() || it->second->snap.state != JobState::queued || !it->second->prepared) {
    local_queue->ack(id);  // cancelled while waiting
    return nullptr;
  }
  std::shared_ptr<Job> job = it->second;
  prepared = std::move(*job->prepared);
  job->prepared.reset();
  return job;
}

// A job taken from the queue becomes running only once its record says so:
// a client that saw "running" then learns after a kill and a restart that it
// was interrupted while running. False if it was cancelled meanwhile (the
// cancellation's own record is written after this one).
bool JobEngine::mark_running(Job& job) {
  std::lock_guard guard(job.store_mutex);
  JobSnapshot s;
  {
    std::lock_guard lock(mutex);
    if (job.snap.state != JobState::queued) return false;
    s = job.snap;
  }
  s.state = JobState::running;
  s.started_at = format_now();
  if (!job.backend->record_running(job, s)) return false;
  std::lock_guard lock(mutex);
  if (job.snap.state != JobState::queued) return false;
  job.snap.state = JobState::running;
  job.snap.started_at = s.started_at;
  announce(job.snap);
  return true;
}

void JobEngine::run(Job& job, PreparedVoxelJob prepared) {
  JobBackend& home = *job.backend;
  JobStore* const store = home.store();
  const std::string id = job.snap.id;
  const auto t0 = std::chrono::steady_clock::now();
  JobSnapshot done;
  bool backend_lost = false;  // the shared backend went away: another replica redoes the job
  try {
    const std::vector<api::AnalysisRequest> analyses = prepared.params.analyses;
    // With analyses to prepare, voxelizing is the first half of the bar.
    if (!analyses.empty()) job.control.set_span(0.0, 0.5);
    JobOutput output;
    VoxelJobResult r;
    // The mesh the thickness on the part is painted on, kept first: the
    // worker is about to hand it to the voxelizer, which turns it.
    if (store) prepared.welded = keep_job_mesh(*store, id, prepared);
    if (prepared.path != ExecutionPath::memory) {
      // Slab by slab straight into the stored RLE: the grid is never whole
      // (only a job with a store streams: job_limits).
      const Grid grid = prepared.grid;
      const std::int64_t slab_layers = prepared.slab_layers;
      // A job of values writes them beside its bits, both at once.
      const std::optional<ValueVolume> type = prepared.params.value_type();
      store->write_volume(id, [&](ByteSink& bits_sink) {
        BitSlabWriter bits(grid, VolumeFormat::rle, EncodeOptions{}, bits_sink);
        const BitSlabConsumer to_bits = [&](std::int64_t k0, const BitVolume& slab) { bits.write(k0, slab); };
        if (prepared.path == ExecutionPath::runs) {
          // Bits only, as runs: the stored RLE is written from them.
          r = execute_voxel_runs_job(std::move(prepared), /*with_report=*/true, &job.control, engine_threads,
                                     [&](std::int64_t k0, const RunSlab& slab) { bits.write(k0, slab); },
                                     bits.preparer());
        } else if (!type) {
          r = execute_streamed_voxel_job(std::move(prepared), /*with_report=*/true, &job.control, engine_threads,
                                         slab_layers, to_bits);
        } else {
          store->write_layer(id, "values", *type, [&](ByteSink& values_sink) {
            ValueSlabWriter values(grid, *type, VolumeFormat::rle, EncodeOptions{}, values_sink);
            r = execute_streamed_voxel_job(std::move(prepared), /*with_report=*/true, &job.control, engine_threads,
                                           slab_layers, to_bits,
                                           [&](std::int64_t k0, const ValueVolume& slab) { values.write(k0, slab); });
            values.finish();
          });
        }
        bits.finish();
      });
      output.rle = store->volume_rle(id);
      if (type) output.values_rle = store->layer_rle(id, "values");
    } else {
      // The mesh report is part of a kept record; a job kept nowhere skips it.
      r = execute_voxel_job(std::move(prepared), /*with_report=*/store != nullptr, &job.control, engine_threads);
      job.control.set_stage("store");
      api::JobVolumes& volumes = output;
      volumes = r.volumes;  // the same volumes, shared: nothing is copied
      if (store) {
        store->save_volume(id, *output.solid);
        if (output.values) store->save_layer(id, "values", *output.values);
        for (const auto& [name, layer] : output.layers) store->save_layer(id, name, *layer);
      }
    }
    // Only a job with a store has analyses (admission refuses them otherwise).
    nlohmann::json analyses_done =
        analyses.empty() ? nlohmann::json::array() : prepare_analyses(job, *store, analyses, r, output);
    const std::uint64_t stored = store ? store->stored_bytes(id) : 0;
    std::lock_guard lock(mutex);
    record_success(job.snap, r, analyses.empty() ? std::nullopt : std::optional(std::move(analyses_done)));
    job.snap.stored_bytes = stored;
    home.succeeded(job, output);
  } catch (const Error& e) {
    std::lock_guard lock(mutex);
    JobSnapshot& s = job.snap;
    if (e.code() == ErrorCode::cancelled) {
      s.state = job.stopped_by_shutdown ? JobState::failed : JobState::cancelled;
      if (job.stopped_by_shutdown) s.failure = interrupted("running");
    } else {
      s.state = JobState::failed;
      if (!api::error_kind(e.code()).client_message) spdlog::error("job {}: {}", s.id, log_safe(e.what()));
      s.failure = failure_of(e);
    }
    s.finished_at = format_now();
  } catch (const StorageFull& e) {
    // Nothing half-written stays: the disk is not kept full by this job.
    spdlog::error("job {}: cannot store its result: {}", id, e.what());
    home.discard_partial(job);
    std::lock_guard lock(mutex);
    job.snap.state = JobState::failed;
    job.snap.finished_at = format_now();
    job.snap.failure = JobFailure{"storage-full", "The service's storage is full",
                                  "the result could not be stored: " + std::string(e.what()) + "; retry later"};
  } catch (const BackendUnavailable& e) {
    warn_backend(e);
    backend_lost = true;
  } catch (const std::exception& e) {
    spdlog::error("job {}: internal error: {}", id, log_safe(e.what()));
    std::lock_guard lock(mutex);
    job.snap.state = JobState::failed;
    job.snap.finished_at = format_now();
    job.snap.failure = internal_failure();
  }
  {
    std::lock_guard lock(mutex);
    if (job.snap.finished_at.empty()) job.snap.finished_at = format_now();
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    recent_job_seconds = 0.8 * recent_job_seconds + 0.2 * seconds;
    done = job.snap;
    home.ended(done);
  }
  job.memory.release();
  home.close_out(job, done, backend_lost);
  deliver();
  finished_cv.notify_all();
}

}  // namespace voxd::server
