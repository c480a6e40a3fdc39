// A huge job spread over the replicas (server/jobs/slab_tasks.h): each slab
// task's layers made and stored by whichever replica takes it, and the job
// put together by the worker that counts the last one done.
#include <spdlog/spdlog.h>

#include "api/error_table.h"
#include "server/jobs/job_engine.h"
#include "server/jobs/job_store.h"
#include "server/jobs/replicated_backend.h"
#include "server/jobs/shared_records.h"
#include "server/jobs/slab_tasks.h"
#include "server/log_safe.h"
#include "voxd/encode/slab_writer.h"

namespace voxd::server {

// One slab task from the shared queue: its layers made and stored, and
// counted done; the worker that counts the last one puts the job together.
void ReplicatedJobBackend::run_slab_task(const TakenJob& taken, const SlabTaskRef& ref) {
  const std::string& qid = taken.id;
  const std::string& id = ref.job_id;
  const std::optional<JobSnapshot> record = parts_.records->load(id);
  if (!record || record->state != JobState::running) {  // ended, deleted or expired: nothing to do
    parts_.queue->ack(qid);
    return;
  }
  const std::optional<SharedSlabTasks::State> state = parts_.slab_tasks ? parts_.slab_tasks->state(id) : std::nullopt;
  if (!state || ref.index >= state->plan.tasks) {
    spdlog::error("slab task {}: its job has no plan for it", qid);
    fail(*record, internal_failure(), qid);
    return;
  }
  if (state->cancel_requested) {
    JobSnapshot s = *record;
    s.state = JobState::cancelled;
    end(std::move(s), {JobState::running}, qid);
    return;
  }
  if (taken.deliveries > parts_.max_deliveries) {
    fail(*record, redelivery_failure(taken.deliveries), qid);
    return;
  }
  auto job = std::make_shared<Job>();
  job->backend = this;
  job->snap = *record;
  job->task_of = id;
  {
    // In the table from now on: a cancellation reaches it while it
    // prepares, and stops it before it makes a voxel.
    std::lock_guard lock(engine_.mutex);
    engine_.jobs[qid] = job;
  }
  // And out of it however the task ends (a shutdown waits for it).
  struct LeaveTable {
    JobEngine& engine;
    const std::string& qid;
    ~LeaveTable() {
      engine.forget_running(qid);
      engine.finished_cv.notify_all();
    }
  } leave{engine_, qid};
  const std::int64_t tasks = state->plan.tasks;
  try {
    std::int64_t done = 0;
    if (parts_.slab_tasks->task_done(id, ref.index)) {
      // Made before, by a worker that stopped before putting the job
      // together: only that is left to do.
      done = parts_.slab_tasks->finish_task(id, ref.index, 0, tasks);
    } else {
      const LayerRange range = state->plan.range(ref.index, record->grid.dims.z);
      spdlog::info("slab task {} running (layers {} to {})", qid, range.begin, range.end - 1);
      std::optional<PreparedVoxelJob> prepared = prepare_again(job, *record, qid, /*with_analyses=*/false);
      if (!prepared) return;
      VoxelJobResult r;
      parts_.slab_tasks->write_blocks(id, ref.index, [&](ByteSink& sink) {
        r = execute_voxel_layers(std::move(*prepared), range, &job->control, engine_.engine_threads,
                                 [&](std::int64_t k0, const RunSlab& slab) { write_rle_layer_blocks(k0, slab, sink); },
                                 prepare_rle_layer_blocks);
      });
      job->memory.release();
      done = parts_.slab_tasks->finish_task(id, ref.index, r.filled, tasks);
      spdlog::info("slab task {} done ({} of {} tasks)", qid, done, tasks);
    }
    if (done == tasks) {
      assemble(job, *record, qid, tasks);
    } else {  // more to come, or the job ended meanwhile (done 0)
      if (done == 0) parts_.slab_tasks->drop_tasks(id);  // blocks stored just after it ended
      parts_.queue->ack(qid);
    }
  } catch (const Error& e) {
    if (e.code() != ErrorCode::cancelled) {
      if (!api::error_kind(e.code()).client_message) spdlog::error("slab task {}: {}", qid, log_safe(e.what()));
      fail(*record, failure_of(e), qid);
    } else if (job->stopped_by_shutdown) {
      parts_.queue->release(qid);  // another replica makes it
    } else {  // a client cancelled (or deleted) the job
      JobSnapshot s = *record;
      s.state = JobState::cancelled;
      end(std::move(s), {JobState::running}, qid);
    }
  } catch (const StorageFull& e) {
    spdlog::error("job {}: cannot store its result: {}", id, e.what());
    fail(*record,
         JobFailure{"storage-full", "The service's storage is full",
                    "the result could not be stored: " + std::string(e.what()) + "; retry later"},
         qid);
  } catch (const BackendUnavailable& e) {
    engine_.warn_backend(e);
    parts_.queue->release(qid);
  } catch (const std::exception& e) {
    const std::optional<JobSnapshot> now = parts_.records->load(id);
    if (now && now->state == JobState::running) {
      spdlog::error("slab task {}: internal error: {}", qid, log_safe(e.what()));
      fail(*record, internal_failure(), qid);
    } else {  // a second worker putting the job together found it ended by the first
      parts_.queue->ack(qid);
    }
  }
}

// A split job's upload read back and prepared again (as at admission), in
// the table under its task's queue id with its memory reserved; nullopt
// when it will not run here (then ended, or handed back).
std::optional<PreparedVoxelJob> ReplicatedJobBackend::prepare_again(const std::shared_ptr<Job>& job,
                                                                    const JobSnapshot& record, const std::string& qid,
                                                                    bool with_analyses) {
  std::optional<SharedJobRecords::Input> input = parts_.records->load_input(record.id);
  if (!input) {
    fail(record, input_expired(), qid);
    return std::nullopt;
  }
  JobLimits limits = engine_.job_limits(true);
  // A slab task only voxelizes its layers: the mesh is welded (for the
  // report) only by the task that finishes the job.
  limits.welds_mesh = with_analyses;
  PreparedVoxelJob prepared = prepare_voxel_job(input->bytes, input->name_hint, *record.job, limits);
  input.reset();
  if (prepared.slab_layers < 1)  // this replica would make it in memory: its tasks stream all the same
    prepared.slab_layers = streamed_job_slab_layers(prepared.grid, prepared.params, limits.stream_slab_bytes);
  std::uint64_t need = prepared_mesh_memory(prepared);
  need += with_analyses ? engine_.analyses_memory(*record.job, prepared)
                        : estimate_streamed_job_memory(prepared.grid, prepared.slab_layers, prepared.triangles);
  if (!reserve(*job, need, qid)) return std::nullopt;
  std::lock_guard lock(engine_.mutex);
  engine_.jobs[qid] = job;
  return prepared;
}

// The last task of a split job counted done: the job's RLE put together
// from its tasks' blocks (head, blocks in z order, tail: the whole job's
// bytes), its report and analyses made as a worker makes them, its end
// recorded. A second worker doing the same (a task made twice) keeps the
// first one's volume and finds the job ended.
void ReplicatedJobBackend::assemble(const std::shared_ptr<Job>& job, const JobSnapshot& record, const std::string& qid,
                                    std::int64_t tasks) {
  const std::string id = record.id;
  std::optional<PreparedVoxelJob> prepared = prepare_again(job, record, qid, /*with_analyses=*/true);
  if (!prepared) return;
  const auto t0 = std::chrono::steady_clock::now();
  const Grid grid = prepared->grid;
  parts_.store->write_volume(id, [&](ByteSink& sink) {
    write_rle_head(grid, sink);
    for (std::int64_t i = 0; i < tasks; ++i) {
      job->control.check_cancelled();
      if (!parts_.slab_tasks->read_blocks(id, i, sink))
        throw std::runtime_error("the blocks of slab task " + std::to_string(i) + " are gone");
    }
    write_rle_tail(grid, sink);
  });
  const double assembly = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  JobOutput output;
  output.rle = parts_.store->volume_rle(id);
  const std::vector<api::AnalysisRequest> analyses = prepared->params.analyses;
  VoxelJobResult r = describe_voxel_job(std::move(*prepared));
  r.filled = parts_.slab_tasks->filled(id);
  if (r.report && record.job)
    if (auto w = api::empty_result_warning(*record.job, r.inside, r.filled, r.report->surface_area))
      r.warnings.push_back(std::move(*w));
  r.timings.add("assemble", assembly);
  nlohmann::json analyses_done = engine_.prepare_analyses(*job, *parts_.store, analyses, r, output);
  JobSnapshot done = record;
  JobEngine::record_success(done, r, analyses.empty() ? std::nullopt : std::optional(std::move(analyses_done)));
  done.stored_bytes = parts_.store->stored_bytes(done.id);
  job->memory.release();
  spdlog::info("job {} put together from {} slab tasks ({} s)", id, tasks, assembly);
  end(std::move(done), {JobState::running}, qid);
}

}  // namespace voxd::server
