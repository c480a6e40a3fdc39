#include "server/jobs/job_manager.h"

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <mutex>
#include <random>
#include <thread>
#include <unordered_map>

#include <spdlog/spdlog.h>

#include "api/error_table.h"
#include "api/param_error.h"
#include "server/jobs/content_hash.h"
#include "server/jobs/job_analyses.h"
#include "voxd/encode/slab_writer.h"
#include "server/jobs/expiry.h"
#include "server/jobs/job_record.h"
#include "server/jobs/job_events.h"
#include "server/jobs/job_queue.h"
#include "server/jobs/job_store.h"
#include "server/jobs/local_job_store.h"
#include "server/jobs/shared_records.h"
#include "server/jobs/slab_tasks.h"
#include "server/jobs/volume_cache.h"
#include "server/log_safe.h"
#include "voxd/error.h"
#include "voxd/parallel.h"

namespace voxd::server {

namespace {

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

// The job's volumes as stored, uncompressed: the bits, its values and the
// layers its mode keeps beside them (RLE is usually far smaller; this is
// the bound a result-size cap is checked against at admission).
std::uint64_t result_volume_bytes(const Grid& grid, const api::JobParams& params) {
  const std::uint64_t voxels = grid.voxel_count();
  std::uint64_t bytes = (voxels + 7) / 8;
  if (const std::optional<ValueVolume> type = params.value_type()) {
    const std::uint64_t value = std::visit([]<typename T>(const DenseVolume<T>&) { return sizeof(T); }, *type);
    bytes += voxels * value * (1 + params.mode->stored_layers().size());
  }
  return bytes;
}

JobFailure interrupted(const char* was) {
  return {"interrupted", "Interrupted by a restart",
          std::string("the job was ") + was + " when the service stopped; submit it again"};
}

}  // namespace

struct Job {
  JobSnapshot snap;
  std::optional<PreparedVoxelJob> prepared;  // until a worker takes it
  JobControl control;
  bool ephemeral = false;           // synchronous job: never stored, dropped after use
  // Taken from a shared queue: its record lives in the shared backend and its
  // end is written there by compare-and-set; this process only runs it.
  bool shared = false;
  // A slab task of a shared job split over the replicas: that job's id (the
  // task's own is its queue id, its key in the table).
  std::string task_of;
  JobOutput result;  // a synchronous job's volumes, for its caller
  bool stopped_by_shutdown = false;  // cancelled because the service stops
  // The job's share of the memory budget (its decoded mesh, volumes and
  // analyses), from acceptance until it ends.
  MemoryBudget::Reservation memory;
  // Serializes this job's store writes with its removal: a worker writing the
  // final record just after a client deleted the finished job must not bring
  // it back on disk (and after a restart, in the API).
  std::mutex store_mutex;
  bool removed = false;  // guarded by store_mutex
};

struct JobManager::Impl {
  explicit Impl(JobManagerConfig c)
      : config(std::move(c)),
        store(config.store ? config.store : std::make_shared<LocalJobStore>(config.data_dir)),
        queue(config.queue ? config.queue : std::make_shared<InProcessJobQueue>(config.queue_size)),
        records(config.records),
        // Synchronous jobs never leave this process: with a shared queue they
        // wait in one of their own.
        local_queue(records ? std::make_shared<InProcessJobQueue>(config.queue_size) : queue),
        events(config.on_state_change),
        budget(config.memory_budget ? config.memory_budget : available_memory() / 10 * 6) {}

  JobManagerConfig config;
  // The seams a shared backend replaces (server/jobs/job_store.h, job_queue.h).
  std::shared_ptr<JobStore> store;
  std::shared_ptr<JobQueue> queue;
  std::shared_ptr<SharedJobRecords> records;  // null: embedded
  std::shared_ptr<JobQueue> local_queue;      // synchronous jobs (all jobs, embedded)
  bool shared() const { return records != nullptr; }
  JobEvents events;
  VolumeCache cache{std::size_t{1} << 30};
  MemoryBudget budget;
  int engine_threads = 0;

  // The job table: every job this process knows, by id.
  mutable std::mutex mutex;
  std::condition_variable finished_cv;  // synchronous callers wait here
  // Every state change and every analysis made ready counts one, for the
  // event streams (wait_for_change); progress moves without counting.
  std::uint64_t changes = 0;
  std::condition_variable changed_cv;
  std::unordered_map<std::string, std::shared_ptr<Job>> jobs;
  std::unordered_map<std::string, std::string> succeeded_by_hash;  // content hash -> job id
  bool accepting = true;
  double recent_job_seconds = 1.0;  // moving average, for Retry-After

  std::vector<std::thread> workers;
  std::unique_ptr<ExpiryTimer> expiry;  // sweeps expired jobs until shutdown
  bool shut_down = false;

  // Shared backend: jobs this replica's workers finished since it started
  // (the per-replica counts), and the keeper that reports the running ones.
  std::uint64_t finished_here[3] = {0, 0, 0};  // succeeded, failed, cancelled; under mutex
  std::thread keeper;
  std::mutex keeper_mutex;
  std::condition_variable keeper_wake;
  bool keeper_stop = false;
  std::atomic<bool> backend_ok{true};
  std::atomic<std::int64_t> backend_warned_at{0};

  // Caller holds mutex: the table's order. Wakes whoever waits for a change.
  void announce(const JobSnapshot& s) {
    events.announce(s);
    note_change();
  }
  void note_change() {  // caller holds mutex
    ++changes;
    changed_cv.notify_all();
  }
  void deliver() { events.deliver(); }                         // caller holds no lock

  void persist(Job& job, const JobSnapshot& s) const {
    if (job.ephemeral) return;
    std::lock_guard guard(job.store_mutex);
    if (job.removed) return;
    try {
      store->save(s);
    } catch (const std::exception& e) {
      spdlog::error("job {}: cannot write its record: {}", s.id, e.what());
    }
  }

  void cache_put(const std::string& id, const JobOutput& output) {
    if (!output.solid) return;  // streamed: kept on disk only
    if (output.values) cache.put(VolumeCache::layer_key(id, "values"), output.values, byte_size(*output.values));
    for (const auto& [name, layer] : output.layers) cache.put(VolumeCache::layer_key(id, name), layer, byte_size(*layer));
    cache.put(id, output.solid, output.solid->byte_size());
  }

  JobSnapshot snapshot_of(const Job& job) const {
    JobSnapshot s = job.snap;
    if (s.state == JobState::running) {
      s.progress = job.control.progress();
      s.stage = job.control.stage();
    }
    return s;
  }

  // The analyses the job JSON asked for, computed now and kept as the
  // routes would keep them. A request the grid cannot answer fails alone;
  // cancellation stops the job.
  nlohmann::json prepare_analyses(Job& job, const std::vector<api::AnalysisRequest>& requests, const VoxelJobResult& r,
                                  const JobOutput& output) {
    nlohmann::json status = analyses_status(requests, job.snap.id, "pending");
    if (requests.empty()) return status;
    JobSnapshot view;
    {
      std::lock_guard lock(mutex);
      view = job.snap;
    }
    view.mesh = r.report;
    view.mesh_mass = r.mesh_mass;
    view.values = r.values_info;
    const std::string id = view.id;
    const ArtifactAccess artifacts{
        id, [this, id](const std::string& key) { return store->load_artifact(id, key); },
        [this, &job, id](const std::string& key, const std::string& bytes) {
          std::lock_guard guard(job.store_mutex);
          if (job.removed) return;
          try {
            store->save_artifact(id, key, bytes);
          } catch (const std::exception& e) {
            spdlog::warn("job {}: cannot keep artifact {}: {}", id, key, e.what());
          }
        }};
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
        job_analysis(requests[i], view, output, artifacts, &job.control);
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

  // Logs a lost backend once every 10 s, not on every retry.
  void warn_backend(const std::exception& e) {
    backend_ok = false;
    const std::int64_t now = std::chrono::duration_cast<std::chrono::seconds>(Clock::now().time_since_epoch()).count();
    std::int64_t last = backend_warned_at.load();
    if (now - last >= 10 && backend_warned_at.compare_exchange_strong(last, now))
      spdlog::warn("shared backend: {} (retrying)", e.what());
  }

  // The limits a job is prepared under: a job that would not fit the per-job
  // memory whole streams where it can; a synchronous one is never stored, so
  // never streamed.
  JobLimits job_limits(bool ephemeral) const {
    JobLimits limits = config.limits;
    limits.stream_above_bytes = ephemeral ? 0 : std::min(limits.stream_above_bytes, config.max_job_memory);
    limits.stream_slab_bytes = std::min(limits.stream_slab_bytes, config.max_job_memory / 4);
    return limits;
  }

  // The most memory the job's analyses take beside its volumes.
  std::uint64_t analyses_memory(const api::JobParams& params, const PreparedVoxelJob& prepared) const {
    std::uint64_t peak = 0;
    for (const api::AnalysisRequest& r : params.analyses) {
      try {
        peak = std::max(peak, analysis_memory_on_job(r, prepared.grid, prepared.streamed, config.max_job_memory));
      } catch (const Error& e) {
        throw Error(e.code(), std::string("analyses: ") + e.what());
      }
    }
    return peak;
  }

  // Ends a shared job by compare-and-set (unless another replica or a client
  // ended it first) and acknowledges the queue entry `qid` it was ended
  // from: the job's own, or one of its slab tasks'.
  // Recorded before it leaves the table: a client never sees the job gone or
  // back to "running" from the backend after seeing its end here.
  void end_shared(JobSnapshot s, std::initializer_list<JobState> from, const std::string& qid) {
    if (s.finished_at.empty()) s.finished_at = format_time(Clock::now());
    if (records->transition(s, from)) {
      {
        std::lock_guard lock(mutex);
        ++finished_here[s.state == JobState::succeeded ? 0 : s.state == JobState::failed ? 1 : 2];
        announce(s);
      }
      records->drop_input(s.id);
      if (qid != s.id && config.slab_tasks) config.slab_tasks->drop_tasks(s.id);
    }
    forget_running(qid);
    queue->ack(qid);
    deliver();
    finished_cv.notify_all();
  }
  // The same for a job that failed (or will not run).
  void fail_shared(const JobSnapshot& record, JobFailure failure, const std::string& qid) {
    JobSnapshot s = record;
    s.state = JobState::failed;
    s.failure = std::move(failure);
    end_shared(std::move(s), {JobState::queued, JobState::running}, qid);
  }
  static JobFailure failure_of(const Error& e) {
    const api::ErrorKind& kind = api::error_kind(e.code());
    return JobFailure{kind.slug, "The job failed", kind.client_message ? e.what() : "the job failed unexpectedly; it was logged"};
  }
  static JobFailure redelivery_failure(int deliveries) {
    return JobFailure{"redelivery-limit", "The job stopped its workers",
                      "the job was handed to a worker " + std::to_string(deliveries) +
                          " times and none finished it (each one's replica stopped while running it); "
                          "it is not tried again: check the service's logs, or submit it again"};
  }
  static JobFailure input_expired() {
    return JobFailure{"input-expired", "The job's upload expired",
                      "the uploaded mesh was no longer kept when a worker took the job; submit it again"};
  }

  // Reserves `need` bytes of this replica's memory for a job taken from the
  // shared queue (admitted by the replica it was submitted to), waiting for
  // them with its lease renewed. False when this process stops meanwhile:
  // the entry `qid` was handed back.
  bool reserve_shared(Job& job, std::uint64_t need, const std::string& qid) {
    for (;;) {
      try {
        job.memory = budget.reserve(need, "the job");
        return true;
      } catch (const MemoryBusy&) {
        if (queue->closed()) {
          queue->release(qid);
          return false;
        }
        queue->renew_leases();
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
      }
    }
  }

  // A job handed out by the shared queue, made ready to run here: its record
  // and upload read back, prepared again (as at admission) and its memory
  // reserved. Null when it is not to run (ended meanwhile, too many
  // deliveries, upload expired): then it was acknowledged.
  std::shared_ptr<Job> adopt(const TakenJob& taken, PreparedVoxelJob& prepared) {
    const std::optional<JobSnapshot> record = records->load(taken.id);
    if (!record || finished(record->state)) {
      queue->ack(taken.id);
      return nullptr;
    }
    if (taken.deliveries > config.max_deliveries) {
      fail_shared(*record, redelivery_failure(taken.deliveries), taken.id);
      return nullptr;
    }
    std::optional<SharedJobRecords::Input> input = records->load_input(taken.id);
    if (!input) {
      fail_shared(*record, input_expired(), taken.id);
      return nullptr;
    }
    auto job = std::make_shared<Job>();
    job->snap = *record;
    job->snap.state = JobState::queued;  // as far as this process is concerned: mark_running moves it on
    job->shared = true;
    try {
      prepared = prepare_voxel_job(input->bytes, input->name_hint, *record->job, job_limits(false));
      const std::uint64_t need = mesh_memory(prepared.mesh) + prepared.memory_estimate + analyses_memory(*record->job, prepared);
      input.reset();
      if (!reserve_shared(*job, need, taken.id)) return nullptr;
    } catch (const Error& e) {
      fail_shared(*record, failure_of(e), taken.id);
      return nullptr;
    }
    std::lock_guard lock(mutex);
    jobs[taken.id] = job;
    return job;
  }

  // --- A huge job spread over the replicas (server/jobs/slab_tasks.h) ---

  // Splits a shared job just marked running into slab tasks when it is a
  // streamed job of bits of more than one task; true when it was: its tasks
  // are then on the queue for every replica, and it leaves this worker.
  bool split(Job& job, const PreparedVoxelJob& prepared) {
    if (!config.slab_tasks || !prepared.streamed || !prepared.params.mode->makes_runs(prepared.params))
      return false;
    const std::optional<SlabTaskPlan> plan = plan_slab_tasks(prepared.grid, prepared.slab_layers, config.slab_task_bytes);
    if (!plan) return false;
    const std::string id = job.snap.id;
    std::vector<std::string> tasks;
    for (std::int64_t i = 0; i < plan->tasks; ++i) tasks.push_back(slab_task_id(id, i));
    try {
      config.slab_tasks->save_plan(id, *plan);
      queue->split(id, tasks);
      spdlog::info("job {} split into {} slab tasks of {} layers", id, plan->tasks, plan->task_layers);
    } catch (const std::exception& e) {
      // Unsplit: the job's entry goes back, and whoever takes it splits it.
      warn_backend(e);
      queue->release(id);
    }
    forget_running(id);
    job.memory.release();
    return true;
  }

  // One slab task from the shared queue: its layers made and stored, and
  // counted done; the worker that counts the last one puts the job together.
  void run_slab_task(const TakenJob& taken, const SlabTaskRef& ref) {
    const std::string& qid = taken.id;
    const std::string& id = ref.job_id;
    const std::optional<JobSnapshot> record = records->load(id);
    if (!record || record->state != JobState::running) {  // ended, deleted or expired: nothing to do
      queue->ack(qid);
      return;
    }
    const std::optional<SharedSlabTasks::State> state = config.slab_tasks ? config.slab_tasks->state(id) : std::nullopt;
    if (!state || ref.index >= state->plan.tasks) {
      spdlog::error("slab task {}: its job has no plan for it", qid);
      fail_shared(*record, JobFailure{"internal", "Internal error", "the job failed unexpectedly; it was logged"}, qid);
      return;
    }
    if (state->cancel_requested) {
      JobSnapshot s = *record;
      s.state = JobState::cancelled;
      end_shared(std::move(s), {JobState::running}, qid);
      return;
    }
    if (taken.deliveries > config.max_deliveries) {
      fail_shared(*record, redelivery_failure(taken.deliveries), qid);
      return;
    }
    auto job = std::make_shared<Job>();
    job->snap = *record;
    job->shared = true;
    job->task_of = id;
    {
      // In the table from now on: a cancellation reaches it while it
      // prepares, and stops it before it makes a voxel.
      std::lock_guard lock(mutex);
      jobs[qid] = job;
    }
    // And out of it however the task ends (a shutdown waits for it).
    struct LeaveTable {
      Impl& m;
      const std::string& qid;
      ~LeaveTable() {
        m.forget_running(qid);
        m.finished_cv.notify_all();
      }
    } leave{*this, qid};
    const std::int64_t tasks = state->plan.tasks;
    try {
      std::int64_t done = 0;
      if (config.slab_tasks->task_done(id, ref.index)) {
        // Made before, by a worker that stopped before putting the job
        // together: only that is left to do.
        done = config.slab_tasks->finish_task(id, ref.index, 0, tasks);
      } else {
        const LayerRange range = state->plan.range(ref.index, record->grid.dims.z);
        spdlog::info("slab task {} running (layers {} to {})", qid, range.begin, range.end - 1);
        std::optional<PreparedVoxelJob> prepared = prepare_shared(job, *record, qid, /*with_analyses=*/false);
        if (!prepared) return;
        VoxelJobResult r;
        config.slab_tasks->write_blocks(id, ref.index, [&](ByteSink& sink) {
          r = execute_voxel_layers(std::move(*prepared), range, &job->control, engine_threads,
                                   [&](std::int64_t k0, const RunSlab& slab) { write_rle_layer_blocks(k0, slab, sink); });
        });
        job->memory.release();
        done = config.slab_tasks->finish_task(id, ref.index, r.filled, tasks);
        spdlog::info("slab task {} done ({} of {} tasks)", qid, done, tasks);
      }
      if (done == tasks) {
        assemble(job, *record, qid, tasks);
      } else {  // more to come, or the job ended meanwhile (done 0)
        if (done == 0) config.slab_tasks->drop_tasks(id);  // blocks stored just after it ended
        queue->ack(qid);
      }
    } catch (const Error& e) {
      if (e.code() != ErrorCode::cancelled) {
        if (!api::error_kind(e.code()).client_message) spdlog::error("slab task {}: {}", qid, log_safe(e.what()));
        fail_shared(*record, failure_of(e), qid);
      } else if (job->stopped_by_shutdown) {
        queue->release(qid);  // another replica makes it
      } else {  // a client cancelled (or deleted) the job
        JobSnapshot s = *record;
        s.state = JobState::cancelled;
        end_shared(std::move(s), {JobState::running}, qid);
      }
    } catch (const StorageFull& e) {
      spdlog::error("job {}: cannot store its result: {}", id, e.what());
      fail_shared(*record, JobFailure{"storage-full", "The service's storage is full",
                                      "the result could not be stored: " + std::string(e.what()) + "; retry later"},
                  qid);
    } catch (const BackendUnavailable& e) {
      warn_backend(e);
      queue->release(qid);
    } catch (const std::exception& e) {
      const std::optional<JobSnapshot> now = records->load(id);
      if (now && now->state == JobState::running) {
        spdlog::error("slab task {}: internal error: {}", qid, log_safe(e.what()));
        fail_shared(*record, JobFailure{"internal", "Internal error", "the job failed unexpectedly; it was logged"}, qid);
      } else {  // a second worker putting the job together found it ended by the first
        queue->ack(qid);
      }
    }
  }

  // A split job's upload read back and prepared again (as at admission), in
  // the table under its task's queue id with its memory reserved; nullopt
  // when it will not run here (then ended, or handed back).
  std::optional<PreparedVoxelJob> prepare_shared(const std::shared_ptr<Job>& job, const JobSnapshot& record,
                                                 const std::string& qid, bool with_analyses) {
    std::optional<SharedJobRecords::Input> input = records->load_input(record.id);
    if (!input) {
      fail_shared(record, input_expired(), qid);
      return std::nullopt;
    }
    PreparedVoxelJob prepared = prepare_voxel_job(input->bytes, input->name_hint, *record.job, job_limits(false));
    input.reset();
    if (prepared.slab_layers < 1)  // this replica would make it in memory: its tasks stream all the same
      prepared.slab_layers = streamed_job_slab_layers(prepared.grid, prepared.params, job_limits(false).stream_slab_bytes);
    std::uint64_t need = mesh_memory(prepared.mesh);
    need += with_analyses ? analyses_memory(*record.job, prepared)
                          : estimate_streamed_job_memory(prepared.grid, prepared.slab_layers, prepared.triangles);
    if (!reserve_shared(*job, need, qid)) return std::nullopt;
    std::lock_guard lock(mutex);
    jobs[qid] = job;
    return prepared;
  }

  // The last task of a split job counted done: the job's RLE put together
  // from its tasks' blocks (head, blocks in z order, tail: the whole job's
  // bytes), its report and analyses made as run() makes them, its end
  // recorded. A second worker doing the same (a task made twice) keeps the
  // first one's volume and finds the job ended.
  void assemble(const std::shared_ptr<Job>& job, const JobSnapshot& record, const std::string& qid,
                std::int64_t tasks) {
    const std::string id = record.id;
    std::optional<PreparedVoxelJob> prepared = prepare_shared(job, record, qid, /*with_analyses=*/true);
    if (!prepared) return;
    const auto t0 = std::chrono::steady_clock::now();
    const Grid grid = prepared->grid;
    store->write_volume(id, [&](ByteSink& sink) {
      write_rle_head(grid, sink);
      for (std::int64_t i = 0; i < tasks; ++i) {
        job->control.check_cancelled();
        if (!config.slab_tasks->read_blocks(id, i, sink))
          throw std::runtime_error("the blocks of slab task " + std::to_string(i) + " are gone");
      }
      write_rle_tail(grid, sink);
    });
    const double assembly = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    JobOutput output;
    output.rle = store->volume_rle(id);
    const std::vector<api::AnalysisRequest> analyses = prepared->params.analyses;
    VoxelJobResult r = describe_voxel_job(std::move(*prepared));
    r.filled = config.slab_tasks->filled(id);
    r.timings.add("assemble", assembly);
    nlohmann::json analyses_done = prepare_analyses(*job, analyses, r, output);
    JobSnapshot done = record;
    record_success(done, r, analyses.empty() ? std::nullopt : std::optional(std::move(analyses_done)));
    job->memory.release();
    spdlog::info("job {} put together from {} slab tasks ({} s)", id, tasks, assembly);
    end_shared(std::move(done), {JobState::running}, qid);
  }

  // A job taken from the queue becomes running only once its record says
  // so: a client that saw "running" then learns after a kill and a restart
  // that it was interrupted while running. False if it was cancelled
  // meanwhile (the cancellation's own record is written after this one).
  bool mark_running(Job& job) {
    std::lock_guard guard(job.store_mutex);
    JobSnapshot s;
    {
      std::lock_guard lock(mutex);
      if (job.snap.state != JobState::queued) return false;
      s = job.snap;
    }
    s.state = JobState::running;
    s.started_at = format_time(Clock::now());
    if (job.shared) {
      // Queued, or running on a replica that stopped: another replica, or a
      // client's cancellation, may have moved it on since it was read.
      if (!records->transition(s, {JobState::queued, JobState::running})) return false;
    } else if (!job.ephemeral && !job.removed) {
      try {
        store->save(s);
      } catch (const std::exception& e) {
        spdlog::error("job {}: cannot write its record: {}", s.id, e.what());
      }
    }
    std::lock_guard lock(mutex);
    if (job.snap.state != JobState::queued) return false;
    job.snap.state = JobState::running;
    job.snap.started_at = s.started_at;
    announce(job.snap);
    return true;
  }

  // The next job for this worker: synchronous ones first (they have a
  // caller waiting), then the shared queue's; nullopt when none came.
  std::optional<TakenJob> next_job(bool* from_shared) {
    *from_shared = false;
    if (!shared()) return queue->take(std::chrono::seconds(1));
    if (auto local = local_queue->take(std::chrono::milliseconds(0))) return local;
    if (queue->closed()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      return std::nullopt;
    }
    auto taken = queue->take(std::chrono::milliseconds(100));
    *from_shared = taken.has_value();
    return taken;
  }

  void work() {
    for (;;) {
      bool from_shared = false;
      std::optional<TakenJob> taken;
      std::shared_ptr<Job> job;
      PreparedVoxelJob prepared;
      try {
        taken = next_job(&from_shared);
        if (!taken) {
          if (queue->closed() && local_queue->closed()) return;  // the service stops
          continue;
        }
        if (from_shared) {
          if (const std::optional<SlabTaskRef> task = parse_slab_task_id(taken->id)) {
            run_slab_task(*taken, *task);
            continue;
          }
          job = adopt(*taken, prepared);
          if (!job) continue;
        }
      } catch (const std::exception& e) {
        warn_backend(e);
        // A job taken but not adopted is handed back (or its lease lapses).
        if (from_shared && taken) queue->release(taken->id);
        std::this_thread::sleep_for(std::chrono::milliseconds(250));
        continue;
      }
      const std::string id = taken->id;
      if (!job) {
        std::lock_guard lock(mutex);
        auto it = jobs.find(id);
        if (it == jobs.end() || it->second->snap.state != JobState::queued || !it->second->prepared) {
          local_queue->ack(id);  // cancelled while waiting
          continue;
        }
        job = it->second;
        prepared = std::move(*job->prepared);
        job->prepared.reset();
      }
      JobQueue& from = job->shared ? *queue : *local_queue;
      if (job->shared && queue->closed()) {  // this process stops: another replica runs it
        forget_running(id);
        job->memory.release();
        queue->release(id);
        continue;
      }
      bool running = false;
      try {
        running = mark_running(*job);
      } catch (const BackendUnavailable& e) {
        warn_backend(e);
      }
      if (!running) {  // cancelled meanwhile (or the backend went away: the lease runs out)
        if (job->shared) forget_running(id);
        job->memory.release();
        try {
          from.ack(id);
        } catch (const std::exception& e) {
          warn_backend(e);
        }
        continue;
      }
      deliver();
      try {
        if (job->shared && split(*job, prepared)) continue;
        run(job.get(), std::move(prepared), from);
      } catch (const std::exception& e) {
        // run() records every failure of the job itself; this is the
        // bookkeeping after it failing (the backend gone mid-way): the
        // worker lives on, and a shared job's lease lapses.
        spdlog::error("job {}: {}", id, log_safe(e.what()));
        if (job->shared) forget_running(id);
      }
    }
  }

  // A job's record once it succeeded with `r`.
  static void record_success(JobSnapshot& s, const VoxelJobResult& r, std::optional<nlohmann::json> analyses_done) {
    if (analyses_done) s.analyses = std::move(*analyses_done);
    s.state = JobState::succeeded;
    // With the state, in one step: an event stream reading between the two
    // would send an end with no finished_at.
    s.finished_at = format_time(Clock::now());
    s.progress = 1.0;
    s.mesh = r.report;
    s.mesh_mass = r.mesh_mass;
    for (auto& t : r.timings.stages)
      if (std::none_of(s.timings.begin(), s.timings.end(), [&](const auto& x) { return x.first == t.first; }))
        s.timings.push_back(t);
    s.filled_voxels = r.filled;
    s.values = r.values_info.is_null() ? nlohmann::json(nullptr) : r.values_info;
  }

  // Requires no lock: drops a shared job this process ran from the table.
  void forget_running(const std::string& id) {
    std::lock_guard lock(mutex);
    jobs.erase(id);
  }

  void run(Job* job, PreparedVoxelJob prepared, JobQueue& from) {
    const std::string id = job->snap.id;
    const auto t0 = std::chrono::steady_clock::now();
    JobSnapshot done;
    bool backend_lost = false;  // the shared backend went away: another replica redoes the job
    try {
      const std::vector<api::AnalysisRequest> analyses = prepared.params.analyses;
      // With analyses to prepare, voxelizing is the first half of the bar.
      if (!analyses.empty()) job->control.set_span(0.0, 0.5);
      JobOutput output;
      VoxelJobResult r;
      if (prepared.streamed) {
        // Slab by slab straight into the stored RLE: the grid is never whole.
        const Grid grid = prepared.grid;
        const std::int64_t slab_layers = prepared.slab_layers;
        // A job of values writes them beside its bits, both at once.
        const std::optional<ValueVolume> type = prepared.params.value_type();
        store->write_volume(job->snap.id, [&](ByteSink& bits_sink) {
          BitSlabWriter bits(grid, VolumeFormat::rle, EncodeOptions{}, bits_sink);
          const BitSlabConsumer to_bits = [&](std::int64_t k0, const BitVolume& slab) { bits.write(k0, slab); };
          if (prepared.params.mode->makes_runs(prepared.params)) {
            // Bits only, as runs: the stored RLE is written from them.
            r = execute_voxel_runs_job(std::move(prepared), /*with_report=*/true, &job->control, engine_threads,
                                       [&](std::int64_t k0, const RunSlab& slab) { bits.write(k0, slab); });
          } else if (!type) {
            r = execute_streamed_voxel_job(std::move(prepared), /*with_report=*/true, &job->control, engine_threads,
                                           slab_layers, to_bits);
          } else {
            store->write_layer(job->snap.id, "values", *type, [&](ByteSink& values_sink) {
              ValueSlabWriter values(grid, *type, VolumeFormat::rle, EncodeOptions{}, values_sink);
              r = execute_streamed_voxel_job(
                  std::move(prepared), /*with_report=*/true, &job->control, engine_threads, slab_layers, to_bits,
                  [&](std::int64_t k0, const ValueVolume& slab) { values.write(k0, slab); });
              values.finish();
            });
          }
          bits.finish();
        });
        output.rle = store->volume_rle(job->snap.id);
        if (type) output.values_rle = store->layer_rle(job->snap.id, "values");
      } else {
        r = execute_voxel_job(std::move(prepared), /*with_report=*/!job->ephemeral, &job->control, engine_threads);
        job->control.set_stage("store");
        output.solid = std::make_shared<const BitVolume>(std::move(r.volume));
        if (r.values) output.values = std::make_shared<const ValueVolume>(std::move(*r.values));
        for (auto& [name, layer] : r.layers)
          output.layers.emplace_back(name, std::make_shared<const ValueVolume>(std::move(layer)));
        if (!job->ephemeral) {
          store->save_volume(job->snap.id, *output.solid);
          if (output.values) store->save_layer(job->snap.id, "values", *output.values);
          for (const auto& [name, layer] : output.layers) store->save_layer(job->snap.id, name, *layer);
        }
      }
      nlohmann::json analyses_done = prepare_analyses(*job, analyses, r, output);
      std::lock_guard lock(mutex);
      JobSnapshot& s = job->snap;
      record_success(s, r, analyses.empty() ? std::nullopt : std::optional(std::move(analyses_done)));
      if (job->ephemeral) {
        job->result = output;
      } else {
        cache_put(s.id, output);
        if (!job->shared) succeeded_by_hash[s.content_hash] = s.id;
      }
    } catch (const Error& e) {
      std::lock_guard lock(mutex);
      JobSnapshot& s = job->snap;
      if (e.code() == ErrorCode::cancelled) {
        s.state = job->stopped_by_shutdown ? JobState::failed : JobState::cancelled;
        if (job->stopped_by_shutdown) s.failure = interrupted("running");
      } else {
        s.state = JobState::failed;
        const api::ErrorKind& kind = api::error_kind(e.code());
        if (!kind.client_message) spdlog::error("job {}: {}", s.id, log_safe(e.what()));
        s.failure = JobFailure{kind.slug, "The job failed",
                               kind.client_message ? e.what() : "the job failed unexpectedly; it was logged"};
      }
      s.finished_at = format_time(Clock::now());
    } catch (const StorageFull& e) {
      // Nothing half-written stays: the disk is not kept full by this job.
      spdlog::error("job {}: cannot store its result: {}", job->snap.id, e.what());
      if (!job->shared) {
        std::lock_guard guard(job->store_mutex);
        if (!job->removed) store->remove(job->snap.id);
      }
      std::lock_guard lock(mutex);
      job->snap.state = JobState::failed;
      job->snap.finished_at = format_time(Clock::now());
      job->snap.failure = JobFailure{"storage-full", "The service's storage is full",
                                     "the result could not be stored: " + std::string(e.what()) + "; retry later"};
    } catch (const BackendUnavailable& e) {
      warn_backend(e);
      backend_lost = true;
    } catch (const std::exception& e) {
      spdlog::error("job {}: internal error: {}", job->snap.id, log_safe(e.what()));
      std::lock_guard lock(mutex);
      job->snap.state = JobState::failed;
      job->snap.finished_at = format_time(Clock::now());
      job->snap.failure = JobFailure{"internal", "Internal error", "the job failed unexpectedly; it was logged"};
    }
    {
      std::lock_guard lock(mutex);
      if (job->snap.finished_at.empty()) job->snap.finished_at = format_time(Clock::now());
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      recent_job_seconds = 0.8 * recent_job_seconds + 0.2 * seconds;
      done = job->snap;
      if (!job->shared) announce(done);
    }
    job->memory.release();
    if (job->shared) {
      finish_shared(*job, done, backend_lost);
    } else {
      persist(*job, done);
      from.ack(id);
    }
    deliver();
    finished_cv.notify_all();
  }

  // A shared job's end: written by compare-and-set (a job run twice ends
  // once), its upload dropped, its queue entry acknowledged. A job this
  // process stops, or whose end cannot be written, is handed back instead.
  void finish_shared(Job& job, const JobSnapshot& done, bool backend_lost) {
    const std::string id = done.id;
    if (!backend_lost && !job.stopped_by_shutdown) {
      try {
        end_shared(done, {JobState::running}, id);
        return;
      } catch (const BackendUnavailable& e) {
        warn_backend(e);
      }
    }
    forget_running(id);
    queue->release(id);  // another replica runs it again
  }

  // Shared backend: every ~100 ms, the running jobs' progress and this
  // replica's heartbeat out, cancellations in, leases renewed.
  void keep() {
    std::unique_lock wait_lock(keeper_mutex);
    while (!keeper_wake.wait_for(wait_lock, std::chrono::milliseconds(100), [&] { return keeper_stop; })) {
      std::vector<SharedJobRecords::RunningReport> running;
      {
        std::lock_guard lock(mutex);
        for (const auto& [id, job] : jobs)
          if (job->shared && job->snap.state == JobState::running) {
            // A slab task reports for its job, leaving its progress to the
            // tasks' count.
            if (job->task_of.empty())
              running.push_back({id, job->control.progress(), job->control.stage(), job->snap.analyses});
            else
              running.push_back({job->task_of, -1.0, "", nullptr});
          }
      }
      try {
        const std::vector<std::string> cancel = records->report_running(running);
        backend_ok = true;
        std::lock_guard lock(mutex);
        for (const std::string& id : cancel) {
          if (auto it = jobs.find(id); it != jobs.end()) it->second->control.request_cancel();
          for (const auto& [key, job] : jobs)
            if (job->task_of == id) job->control.request_cancel();
        }
      } catch (const std::exception& e) {
        warn_backend(e);
      }
      try {
        queue->renew_leases();
      } catch (const std::exception& e) {
        warn_backend(e);
      }
    }
  }

  std::size_t expire() {
    if (shared()) {
      // The backend expires records and results itself; its index is pruned.
      try {
        records->prune();
      } catch (const std::exception& e) {
        warn_backend(e);
      }
      return 0;
    }
    const auto now = Clock::now();
    std::vector<std::shared_ptr<Job>> victims;
    {
      std::lock_guard lock(mutex);
      for (const auto& [id, job] : jobs)
        if (expired(job->snap, now, config.result_ttl)) victims.push_back(job);
      for (const auto& job : victims) forget(job->snap.id);
    }
    for (const auto& job : victims) remove_from_store(*job);
    return victims.size();
  }

  void remove_from_store(Job& job) const {
    std::lock_guard guard(job.store_mutex);
    job.removed = true;
    store->remove(job.snap.id);
  }

  // Requires the lock.
  void forget(const std::string& id) {
    auto it = jobs.find(id);
    if (it == jobs.end()) return;
    auto h = succeeded_by_hash.find(it->second->snap.content_hash);
    if (h != succeeded_by_hash.end() && h->second == id) succeeded_by_hash.erase(h);
    cache.drop_job(id);
    jobs.erase(it);
  }

  // A job's current snapshot: from the table (every job, embedded; the jobs
  // running here, shared) or the shared records. Synchronous jobs are not
  // found: they have no routes.
  std::optional<JobSnapshot> find(const std::string& id) const {
    {
      std::lock_guard lock(mutex);
      auto it = jobs.find(id);
      if (it != jobs.end()) {
        if (it->second->ephemeral) return std::nullopt;
        // A shared job is shown from here only while it runs (its live
        // progress); its end counts once it is recorded in the backend.
        if (!it->second->shared || it->second->snap.state == JobState::running) return snapshot_of(*it->second);
      }
    }
    if (shared()) return records->load(id);
    return std::nullopt;
  }
  bool succeeded(const std::string& id) const {
    const auto s = find(id);
    return s && s->state == JobState::succeeded;
  }

  int retry_after() const {
    const int workers_n = std::max<int>(1, static_cast<int>(workers.size()));
    const double seconds = recent_job_seconds * static_cast<double>(queue->depth() + 1) / workers_n;
    return std::clamp(static_cast<int>(std::ceil(seconds)), 1, 3600);
  }

  RemoveResult cancel_or_delete_shared(const std::string& id);
  std::shared_ptr<Job> enqueue(std::vector<std::uint8_t>& mesh_bytes, const std::string& name_hint,
                               const nlohmann::json& params_json, bool ephemeral, JobSnapshot* cached_out,
                               std::uint64_t max_voxels = 0);
};

JobManager::JobManager(JobManagerConfig config) : impl_(std::make_unique<Impl>(std::move(config))) {
  Impl& m = *impl_;
  // Jobs a previous process left queued or running are reported failed with
  // reason "interrupted" rather than silently re-run: a client polling them
  // learns what happened and decides whether to resubmit.
  // Shared records belong to every replica: none is this process's to mark.
  for (JobSnapshot s : m.shared() ? std::vector<JobSnapshot>{} : m.store->load_all()) {
    if (!finished(s.state)) {
      s.failure = interrupted(s.state == JobState::queued ? "queued" : "running");
      s.state = JobState::failed;
      s.finished_at = format_time(Clock::now());
      m.store->save(s);
    }
    if (s.state == JobState::succeeded) {
      auto prev = m.succeeded_by_hash.find(s.content_hash);
      if (prev == m.succeeded_by_hash.end() || m.jobs.at(prev->second)->snap.created_at < s.created_at)
        m.succeeded_by_hash[s.content_hash] = s.id;
    }
    auto job = std::make_shared<Job>();
    job->snap = std::move(s);
    m.jobs.emplace(job->snap.id, job);
  }
  const int n = m.config.workers > 0 ? m.config.workers : default_thread_count();
  // Each job's engine may use every core: a lone big job should not wait on
  // idle cores, and two concurrent ones share them through the scheduler.
  m.engine_threads = 0;
  for (int i = 0; i < n; ++i) m.workers.emplace_back([&m] { m.work(); });
  m.expiry = std::make_unique<ExpiryTimer>(m.config.result_ttl, [&m] { m.expire(); });
  if (m.shared()) {
    // Counted among the live replicas from the start, not a tick later.
    try {
      m.records->report_running({});
    } catch (const std::exception& e) {
      m.warn_backend(e);
    }
    m.keeper = std::thread([&m] { m.keep(); });
  }
}

JobManager::~JobManager() { shutdown(std::chrono::seconds(0)); }

std::shared_ptr<Job> JobManager::Impl::enqueue(std::vector<std::uint8_t>& mesh_bytes, const std::string& name_hint,
                                               const nlohmann::json& params_json, bool ephemeral,
                                               JobSnapshot* cached_out, std::uint64_t max_voxels) {
  // Synchronous jobs wait in this process; with a shared backend the others
  // wait in its queue, for any replica.
  const bool to_shared = shared() && !ephemeral;
  JobQueue& target = to_shared ? *queue : *local_queue;
  {
    std::lock_guard lock(mutex);
    if (!accepting) throw NotAccepting("the service is shutting down and accepts no new jobs");
  }
  if (target.depth() >= config.queue_size)
    throw QueueFull("the job queue is full (" + std::to_string(config.queue_size) + " jobs waiting); retry later",
                    retry_after());
  const auto parsed = std::make_shared<const api::JobParams>(api::parse_job_params(params_json));
  const api::JobParams& params = *parsed;
  if (!ephemeral && store->free_bytes() < config.min_free_disk)
    throw StorageFull("the service's storage has less than " + std::to_string(config.min_free_disk >> 20) +
                      " MiB free and takes no new jobs until results expire or are deleted; retry later");
  // Synchronous jobs are never stored, so never answered from the store: they
  // skip the hash (a tenth of a small job's time).
  const std::string hash = ephemeral ? std::string() : content_hash(mesh_bytes, params_json.dump());

  // An identical earlier submission that succeeded answers this one.
  if (!ephemeral && cached_out) {
    std::optional<JobSnapshot> original;
    if (to_shared) {
      if (const auto id = records->succeeded_with_hash(hash)) {
        original = records->load(*id);
        if (original && original->state != JobState::succeeded) original.reset();
      }
    } else {
      std::lock_guard lock(mutex);
      auto h = succeeded_by_hash.find(hash);
      if (h != succeeded_by_hash.end()) original = jobs.at(h->second)->snap;
    }
    if (original) {
      JobSnapshot s = *original;
      s.id = new_job_id();
      s.created_at = s.started_at = s.finished_at = format_time(Clock::now());
      s.params = params_json;
      s.job = parsed;
      s.cached = true;
      s.timings.clear();
      s.analyses = analyses_status(params.analyses, s.id, "on_request");
      try {
        store->share_volume(original->id, s.id);
        store->save(s);
        if (!to_shared) {
          auto job = std::make_shared<Job>();
          job->snap = s;
          std::lock_guard lock(mutex);
          jobs.emplace(s.id, job);
        }
        *cached_out = s;
        return nullptr;
      } catch (const BackendUnavailable&) {
        throw;
      } catch (const std::exception& e) {
        // The original was deleted meanwhile: fall through and compute.
        store->remove(s.id);
        spdlog::info("job cache miss for {}: {}", original->id, e.what());
      }
    }
  }

  if (ephemeral && !params.analyses.empty())
    throw api::InvalidParams(std::vector<api::FieldError>{
        {"/analyses", "synchronous voxelization answers with the volume only; submit to POST /v1/jobs for analyses"}});
  // The upload while it is decoded, then the job's own share: until the
  // decoded mesh is known, a bound from the bytes and the format.
  MemoryBudget::Reservation decoding =
      budget.reserve(decode_memory_estimate(mesh_bytes, name_hint, config.limits.decode), "decoding this upload");
  PreparedVoxelJob prepared = prepare_voxel_job(mesh_bytes, name_hint, params, job_limits(ephemeral));
  if (max_voxels > 0 && prepared.grid.voxel_count() > max_voxels)
    throw Error(ErrorCode::limit_exceeded, "the grid has " + std::to_string(prepared.grid.voxel_count()) +
                                               " voxels; synchronous voxelization takes at most " +
                                               std::to_string(max_voxels) + ": submit it to POST /v1/jobs instead");
  if (prepared.memory_estimate > config.max_job_memory)
    throw Error(ErrorCode::limit_exceeded,
                "the job needs about " + std::to_string(prepared.memory_estimate >> 20) + " MiB for its volumes, over the limit of " +
                    std::to_string(config.max_job_memory >> 20) + " MiB; use a lower resolution or a larger voxel_size");
  if (!ephemeral && config.max_result_bytes > 0) {
    const std::uint64_t bytes = result_volume_bytes(prepared.grid, params);
    if (bytes > config.max_result_bytes)
      throw Error(ErrorCode::limit_exceeded,
                  "the job's volumes take up to " + std::to_string(bytes >> 20) + " MiB to store, over the service's cap of " +
                      std::to_string(config.max_result_bytes >> 20) +
                      " MiB a result; use a lower resolution or a larger voxel_size");
  }
  const std::uint64_t analyses_peak = analyses_memory(params, prepared);
  MemoryBudget::Reservation memory;
  if (!to_shared) {
    mesh_bytes.clear();
    mesh_bytes.shrink_to_fit();
    decoding.release();
    memory = budget.reserve(mesh_memory(prepared.mesh) + prepared.memory_estimate + analyses_peak, "the job");
  }

  auto job = std::make_shared<Job>();
  job->memory = std::move(memory);
  job->ephemeral = ephemeral;
  JobSnapshot& s = job->snap;
  s.id = new_job_id();
  s.state = JobState::queued;
  s.created_at = format_time(Clock::now());
  s.params = params_json;
  s.job = parsed;
  s.mesh_format = to_string(prepared.format);
  s.triangles = prepared.triangles;
  s.grid = prepared.grid;
  s.streamed = prepared.streamed;
  s.timings = prepared.timings.stages;
  s.content_hash = hash;
  s.analyses = analyses_status(params.analyses, s.id, "pending");
  if (to_shared) {
    // Whichever replica takes it prepares it again from the stored upload:
    // only the record and the bytes travel.
    prepared = PreparedVoxelJob{};
    store->save(s);
    try {
      records->save_input(s.id, mesh_bytes, name_hint);
      mesh_bytes.clear();
      mesh_bytes.shrink_to_fit();
      if (!queue->submit(s.id)) {
        store->remove(s.id);
        throw QueueFull("the job queue is full (" + std::to_string(config.queue_size) + " jobs waiting); retry later",
                        retry_after());
      }
    } catch (const QueueFull&) {
      throw;
    } catch (...) {
      try {
        store->remove(s.id);
      } catch (const std::exception&) {
        // The backend is away: the record without an entry expires with nothing.
      }
      throw;
    }
    {
      std::lock_guard lock(mutex);
      announce(s);
    }
    deliver();
    return job;
  }
  job->prepared = std::move(prepared);
  // Recorded before a worker can see it, so the final record always wins. A
  // job that cannot be recorded is not accepted (a full disk is a 507).
  if (!ephemeral) store->save(s);
  {
    std::lock_guard lock(mutex);
    // Queued under the table's lock: a worker that takes it at once finds it.
    const bool closing = !accepting;
    if (closing || !target.submit(s.id)) {
      const int wait = retry_after();
      if (!ephemeral) store->remove(s.id);
      if (closing) throw NotAccepting("the service is shutting down and accepts no new jobs");
      throw QueueFull("the job queue is full (" + std::to_string(config.queue_size) + " jobs waiting); retry later", wait);
    }
    jobs.emplace(s.id, job);
    announce(s);
  }
  deliver();
  return job;
}

JobSnapshot JobManager::submit(std::vector<std::uint8_t> mesh_bytes, const std::string& name_hint,
                               const nlohmann::json& params_json) {
  JobSnapshot cached;
  auto job = impl_->enqueue(mesh_bytes, name_hint, params_json, false, &cached);
  if (!job) {
    {
      std::lock_guard lock(impl_->mutex);
      impl_->announce(cached);
    }
    impl_->deliver();
    return cached;
  }
  std::lock_guard lock(impl_->mutex);
  return impl_->snapshot_of(*job);
}

std::optional<JobSnapshot> JobManager::get(const std::string& id) const { return impl_->find(id); }

std::uint64_t JobManager::wait_for_change(std::uint64_t seen, std::chrono::milliseconds timeout) const {
  std::unique_lock lock(impl_->mutex);
  impl_->changed_cv.wait_for(lock, timeout, [&] { return impl_->changes != seen; });
  return impl_->changes;
}

std::vector<JobSnapshot> JobManager::list(std::size_t offset, std::size_t limit, std::size_t* total) const {
  if (impl_->shared()) {
    std::vector<JobSnapshot> page = impl_->records->list(offset, limit, total);
    // Those running here show their live progress.
    std::lock_guard lock(impl_->mutex);
    for (JobSnapshot& s : page)
      if (auto it = impl_->jobs.find(s.id); it != impl_->jobs.end() && it->second->snap.state == JobState::running) s = impl_->snapshot_of(*it->second);
    return page;
  }
  std::vector<JobSnapshot> all;
  {
    std::lock_guard lock(impl_->mutex);
    for (const auto& [id, job] : impl_->jobs)
      if (!job->ephemeral) all.push_back(impl_->snapshot_of(*job));
  }
  std::sort(all.begin(), all.end(), [](const JobSnapshot& a, const JobSnapshot& b) {
    return a.created_at != b.created_at ? a.created_at > b.created_at : a.id > b.id;
  });
  if (total) *total = all.size();
  if (offset >= all.size()) return {};
  const auto first = all.begin() + static_cast<std::ptrdiff_t>(offset);
  return {first, first + static_cast<std::ptrdiff_t>(std::min(limit, all.size() - offset))};
}

JobManager::RemoveResult JobManager::Impl::cancel_or_delete_shared(const std::string& id) {
  {
    std::lock_guard lock(mutex);
    auto it = jobs.find(id);
    if (it != jobs.end()) {
      if (it->second->ephemeral) return RemoveResult::not_found;
      if (it->second->snap.state == JobState::running) {
        it->second->control.request_cancel();  // running here: the worker records the end
        return RemoveResult::cancelled;
      }
    }
  }
  std::optional<JobSnapshot> record = records->load(id);
  if (!record) return RemoveResult::not_found;
  if (record->state == JobState::queued) {
    JobSnapshot s = *record;
    s.state = JobState::cancelled;
    s.finished_at = format_time(Clock::now());
    if (records->transition(s, {JobState::queued})) {
      queue->cancel(id);
      records->drop_input(id);
      {
        std::lock_guard lock(mutex);
        announce(s);
      }
      deliver();
      return RemoveResult::cancelled;
    }
    record = records->load(id);  // taken meanwhile
    if (!record) return RemoveResult::not_found;
  }
  if (record->state == JobState::running) {
    // Whichever replica runs it sees the request within ~100 ms.
    records->request_cancel(id);
    return RemoveResult::cancelled;
  }
  store->remove(id);
  cache.drop_job(id);
  return RemoveResult::deleted;
}

JobManager::RemoveResult JobManager::cancel_or_delete(const std::string& id) {
  if (impl_->shared()) return impl_->cancel_or_delete_shared(id);
  std::optional<JobSnapshot> cancelled;
  std::shared_ptr<Job> target;
  {
    std::lock_guard lock(impl_->mutex);
    auto it = impl_->jobs.find(id);
    if (it == impl_->jobs.end() || it->second->ephemeral) return RemoveResult::not_found;
    target = it->second;
    Job& job = *target;
    if (job.snap.state == JobState::queued) {
      impl_->queue->cancel(id);
      job.snap.state = JobState::cancelled;
      job.snap.finished_at = format_time(Clock::now());
      job.prepared.reset();
      job.memory.release();
      cancelled = job.snap;
      impl_->announce(job.snap);
    } else if (job.snap.state == JobState::running) {
      job.control.request_cancel();  // the worker records the end state
      return RemoveResult::cancelled;
    } else {
      impl_->forget(id);
    }
  }
  if (cancelled) {
    impl_->persist(*target, *cancelled);
    impl_->deliver();
    impl_->finished_cv.notify_all();
    return RemoveResult::cancelled;
  }
  impl_->remove_from_store(*target);
  return RemoveResult::deleted;
}

std::optional<std::string> JobManager::load_artifact(const std::string& id, const std::string& key) const {
  return impl_->store->load_artifact(id, key);
}

void JobManager::save_artifact(const std::string& id, const std::string& key, const std::string& bytes) {
  if (impl_->shared()) {
    // The store keeps it only while the job's record is there.
    try {
      impl_->store->save_artifact(id, key, bytes);
    } catch (const std::exception& e) {
      spdlog::warn("job {}: cannot keep artifact {}: {}", id, key, e.what());
    }
    return;
  }
  std::shared_ptr<Job> job;
  {
    std::lock_guard lock(impl_->mutex);
    auto it = impl_->jobs.find(id);
    if (it == impl_->jobs.end() || it->second->ephemeral) return;
    job = it->second;
  }
  std::lock_guard guard(job->store_mutex);
  if (job->removed) return;  // deleted meanwhile: do not bring its directory back
  try {
    impl_->store->save_artifact(id, key, bytes);
  } catch (const std::exception& e) {
    spdlog::warn("job {}: cannot keep artifact {}: {}", id, key, e.what());
  }
}

std::shared_ptr<const BitVolume> JobManager::volume(const std::string& id) {
  if (!impl_->succeeded(id)) return nullptr;
  if (auto v = impl_->cache.get<BitVolume>(id)) return v;
  auto v = impl_->store->load_volume(id);
  if (v) {
    std::lock_guard lock(impl_->mutex);
    if (impl_->shared() || impl_->jobs.count(id)) impl_->cache.put(id, v, v->byte_size());
  }
  return v;
}

std::shared_ptr<const MappedFile> JobManager::volume_rle(const std::string& id) {
  if (!impl_->succeeded(id)) return nullptr;
  return impl_->store->volume_rle(id);
}

std::shared_ptr<const MappedFile> JobManager::values_rle(const std::string& id) {
  const auto s = impl_->find(id);
  if (!s || s->state != JobState::succeeded || !s->has_value_volume()) return nullptr;
  return impl_->store->layer_rle(id, "values");
}

std::uint64_t JobManager::max_job_memory() const { return impl_->config.max_job_memory; }

std::shared_ptr<const ValueVolume> JobManager::values(const std::string& id) {
  const auto s = impl_->find(id);
  if (!s || !s->has_value_volume()) return nullptr;
  return layer(id, "values");
}

std::shared_ptr<const ValueVolume> JobManager::layer(const std::string& id, const std::string& name) {
  const std::string key = VolumeCache::layer_key(id, name);
  if (!impl_->succeeded(id)) return nullptr;
  if (auto v = impl_->cache.get<ValueVolume>(key)) return v;
  auto v = impl_->store->load_layer(id, name);
  if (v) {
    std::lock_guard lock(impl_->mutex);
    if (impl_->shared() || impl_->jobs.count(id)) impl_->cache.put(key, v, byte_size(*v));
  }
  return v;
}

JobOutput JobManager::run_sync(std::vector<std::uint8_t> mesh_bytes, const std::string& name_hint,
                               const nlohmann::json& params_json, JobSnapshot* snapshot, std::uint64_t max_voxels,
                               const std::function<bool()>& abandoned) {
  std::shared_ptr<Job> job = impl_->enqueue(mesh_bytes, name_hint, params_json, true, nullptr, max_voxels);
  std::unique_lock lock(impl_->mutex);
  bool cancelled = false;
  while (!impl_->finished_cv.wait_for(lock, std::chrono::milliseconds(100), [&] { return finished(job->snap.state); })) {
    if (cancelled || !abandoned) continue;
    lock.unlock();
    const bool gone = abandoned();
    lock.lock();
    if (!gone || finished(job->snap.state)) continue;
    cancelled = true;
    spdlog::info("job {}: the client of a synchronous request went away; cancelling", job->snap.id);
    if (job->snap.state == JobState::queued) {
      impl_->local_queue->cancel(job->snap.id);
      job->snap.state = JobState::cancelled;  // the worker skips it
      job->snap.finished_at = format_time(Clock::now());
      job->prepared.reset();
      job->memory.release();
    } else {
      job->control.request_cancel();
    }
  }
  if (snapshot) *snapshot = job->snap;
  impl_->jobs.erase(job->snap.id);
  return job->snap.state == JobState::succeeded ? job->result : JobOutput{};
}

JobCounts JobManager::counts() const {
  JobCounts c;
  if (impl_->shared()) {
    {
      std::lock_guard lock(impl_->mutex);
      for (const auto& [id, job] : impl_->jobs)
        if (job->shared && job->snap.state == JobState::running) ++c.running;
      c.succeeded = impl_->finished_here[0];
      c.failed = impl_->finished_here[1];
      c.cancelled = impl_->finished_here[2];
    }
    try {
      c.queue_depth = impl_->queue->depth();
      c.live_replicas = impl_->records->live_replicas();
    } catch (const std::exception& e) {
      impl_->warn_backend(e);
      c.live_replicas = 0;
    }
    return c;
  }
  std::lock_guard lock(impl_->mutex);
  for (const auto& [id, job] : impl_->jobs) {
    switch (job->snap.state) {
      case JobState::queued: ++c.queued; break;
      case JobState::running: ++c.running; break;
      case JobState::succeeded: ++c.succeeded; break;
      case JobState::failed: ++c.failed; break;
      case JobState::cancelled: ++c.cancelled; break;
    }
  }
  c.queue_depth = impl_->queue->depth();
  return c;
}

MemoryBudget::Reservation JobManager::reserve_memory(std::uint64_t bytes, const std::string& what) {
  return impl_->budget.reserve(bytes, what);
}

std::uint64_t JobManager::memory_budget() const { return impl_->budget.total(); }
std::uint64_t JobManager::memory_in_use() const { return impl_->budget.used(); }
bool JobManager::storage_ok() const {
  try {
    return impl_->store->free_bytes() >= impl_->config.min_free_disk;
  } catch (const std::exception& e) {
    impl_->warn_backend(e);
    return false;
  }
}

bool JobManager::backend_ok() const { return !impl_->shared() || impl_->backend_ok.load(); }

bool JobManager::accepting() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->accepting;
}

void JobManager::shutdown(std::chrono::seconds deadline) {
  Impl& m = *impl_;
  std::vector<JobSnapshot> abandoned;
  {
    std::unique_lock lock(m.mutex);
    if (m.shut_down) return;
    m.shut_down = true;
    m.accepting = false;
    // Queued jobs will not run in this process: record them as interrupted.
    // (A shared queue's stay there, for the other replicas.)
    std::vector<std::string> left = m.local_queue->close();
    if (m.shared()) m.queue->close();
    for (const std::string& id : left) {
      auto it = m.jobs.find(id);
      if (it == m.jobs.end()) continue;
      const std::shared_ptr<Job>& job = it->second;
      if (job->snap.state != JobState::queued) continue;
      job->snap.state = JobState::failed;
      job->snap.failure = interrupted("queued");
      job->snap.finished_at = format_time(Clock::now());
      job->prepared.reset();
      job->memory.release();
      abandoned.push_back(job->snap);
      m.announce(job->snap);
    }
    auto running = [&] {
      for (const auto& [id, job] : m.jobs)
        if (job->snap.state == JobState::running) return true;
      return false;
    };
    if (!m.finished_cv.wait_for(lock, deadline, [&] { return !running(); })) {
      for (auto& [id, job] : m.jobs)
        if (job->snap.state == JobState::running) {
          job->stopped_by_shutdown = true;
          job->control.request_cancel();
        }
      m.finished_cv.wait(lock, [&] { return !running(); });
    }
  }
  for (const auto& s : abandoned)
    if (!s.content_hash.empty()) m.store->save(s);  // synchronous jobs (no hash) are never stored
  m.deliver();
  m.finished_cv.notify_all();
  for (auto& t : m.workers) t.join();
  m.expiry.reset();
  if (m.keeper.joinable()) {
    {
      std::lock_guard lock(m.keeper_mutex);
      m.keeper_stop = true;
    }
    m.keeper_wake.notify_all();
    m.keeper.join();
  }
}

std::size_t JobManager::expire_now() { return impl_->expire(); }

}  // namespace voxd::server
