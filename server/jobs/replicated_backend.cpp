#include "server/jobs/replicated_backend.h"

#include "server/jobs/kept_mesh.h"

#include <thread>

#include <spdlog/spdlog.h>

#include "server/jobs/job_engine.h"
#include "server/jobs/job_store.h"
#include "server/jobs/shared_records.h"
#include "server/jobs/slab_tasks.h"

namespace voxd::server {

JobFailure redelivery_failure(int deliveries) {
  return JobFailure{"redelivery-limit", "The job stopped its workers",
                    "the job was handed to a worker " + std::to_string(deliveries) +
                        " times and none finished it (each one's replica stopped while running it); "
                        "it is not tried again: check the service's logs, or submit it again"};
}

JobFailure input_expired() {
  return JobFailure{"input-expired", "The job's upload expired",
                    "the uploaded mesh was no longer kept when a worker took the job; submit it again"};
}

namespace {
std::int64_t steady_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
// The keeper reports every 100 ms: silence this long is a backend that does
// not answer (paused, partitioned), even while no call has failed yet.
constexpr std::int64_t kContactStaleNs = std::int64_t{2'000'000'000};
}  // namespace

JobBackendFactory replicated_backend(ReplicatedBackendParts parts) {
  return [parts = std::move(parts)](JobEngine& engine) -> std::unique_ptr<JobBackend> {
    return std::make_unique<ReplicatedJobBackend>(engine, parts);
  };
}

ReplicatedJobBackend::ReplicatedJobBackend(JobEngine& engine, ReplicatedBackendParts parts)
    : engine_(engine), parts_(std::move(parts)) {}

std::optional<JobSnapshot> ReplicatedJobBackend::earlier_success(const std::string& hash) const {
  const std::optional<std::string> id = parts_.records->succeeded_with_hash(hash);
  if (!id) return std::nullopt;
  std::optional<JobSnapshot> original = parts_.records->load(*id);
  if (original && original->state != JobState::succeeded) original.reset();
  return original;
}

void ReplicatedJobBackend::accept(Admitted admitted) {
  // Whichever replica takes it prepares it again from the stored upload:
  // only the record and the bytes travel, and that replica reserves its
  // memory.
  admitted.prepared = PreparedVoxelJob{};
  const JobSnapshot& s = admitted.job->snap;
  parts_.store->save(s);
  try {
    parts_.records->save_input(s.id, admitted.mesh_bytes, admitted.name_hint);
    admitted.mesh_bytes.clear();
    admitted.mesh_bytes.shrink_to_fit();
    if (!parts_.queue->submit(s.id)) {
      parts_.store->remove(s.id);
      throw engine_.queue_full(parts_.queue->depth());
    }
  } catch (const QueueFull&) {
    throw;
  } catch (...) {
    try {
      parts_.store->remove(s.id);
    } catch (const std::exception&) {
      // The backend is away: the record without an entry expires with nothing.
    }
    throw;
  }
  {
    std::lock_guard lock(engine_.mutex);
    engine_.announce(s);
  }
  engine_.deliver();
}

// Synchronous jobs first (they have a caller waiting), then the shared
// queue's.
JobBackend::Next ReplicatedJobBackend::next(std::shared_ptr<Job>& job, PreparedVoxelJob& prepared) {
  JobQueue& queue = *parts_.queue;
  std::optional<TakenJob> taken;
  try {
    if (const std::optional<TakenJob> local = engine_.local_queue->take(std::chrono::milliseconds(0))) {
      job = engine_.take_local(local->id, prepared);
      return job ? Next::job : Next::none;
    }
    if (queue.closed()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      return engine_.local_queue->closed() ? Next::stopped : Next::none;
    }
    taken = queue.take(std::chrono::milliseconds(100));
    if (!taken) return queue.closed() && engine_.local_queue->closed() ? Next::stopped : Next::none;
    if (const std::optional<SlabTaskRef> task = parse_slab_task_id(taken->id)) {
      run_slab_task(*taken, *task);
      return Next::none;
    }
    job = adopt(*taken, prepared);
    if (!job) return Next::none;
  } catch (const std::exception& e) {
    engine_.warn_backend(e);
    // A job taken but not adopted is handed back (or its lease lapses).
    if (taken) queue.release(taken->id);
    std::this_thread::sleep_for(std::chrono::milliseconds(250));
    return Next::none;
  }
  if (queue.closed()) {  // this process stops: another replica runs it
    engine_.forget_running(taken->id);
    job->memory.release();
    queue.release(taken->id);
    return Next::none;
  }
  return Next::job;
}

// Reserves `need` bytes of this replica's memory for a job taken from the
// shared queue (admitted by the replica it was submitted to), waiting for
// them with its lease renewed. False when this process stops meanwhile: the
// entry `qid` was handed back.
bool ReplicatedJobBackend::reserve(Job& job, std::uint64_t need, const std::string& qid) {
  for (;;) {
    try {
      job.memory = engine_.budget.reserve(need, "the job");
      return true;
    } catch (const MemoryBusy&) {
      if (parts_.queue->closed()) {
        parts_.queue->release(qid);
        return false;
      }
      parts_.queue->renew_leases();
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  }
}

// A job handed out by the shared queue, made ready to run here: its record
// and upload read back, prepared again (as at admission) and its memory
// reserved. Null when it is not to run (ended meanwhile, too many
// deliveries, upload expired): then it was acknowledged.
std::shared_ptr<Job> ReplicatedJobBackend::adopt(const TakenJob& taken, PreparedVoxelJob& prepared) {
  const std::optional<JobSnapshot> record = parts_.records->load(taken.id);
  if (!record || finished(record->state)) {
    parts_.queue->ack(taken.id);
    return nullptr;
  }
  if (taken.deliveries > parts_.max_deliveries) {
    fail(*record, redelivery_failure(taken.deliveries), taken.id);
    return nullptr;
  }
  std::optional<SharedJobRecords::Input> input = parts_.records->load_input(taken.id);
  if (!input) {
    fail(*record, input_expired(), taken.id);
    return nullptr;
  }
  auto job = std::make_shared<Job>();
  job->backend = this;
  job->snap = *record;
  job->snap.state = JobState::queued;  // as far as this process is concerned: mark_running moves it on
  try {
    prepared = prepare_voxel_job(input->bytes, input->name_hint, *record->job, engine_.job_limits(true));
    const std::uint64_t need =
        prepared_mesh_memory(prepared) + prepared.memory_estimate + engine_.analyses_memory(*record->job, prepared);
    input.reset();
    if (!reserve(*job, need, taken.id)) return nullptr;
  } catch (const Error& e) {
    fail(*record, failure_of(e), taken.id);
    return nullptr;
  }
  std::lock_guard lock(engine_.mutex);
  engine_.jobs[taken.id] = job;
  return job;
}

bool ReplicatedJobBackend::record_running(Job&, const JobSnapshot& running) {
  // Queued, or running on a replica that stopped: another replica, or a
  // client's cancellation, may have moved it on since it was read.
  return parts_.records->transition(running, {JobState::queued, JobState::running});
}

void ReplicatedJobBackend::drop_taken(Job& job) {
  const std::string id = job.snap.id;
  engine_.forget_running(id);
  try {
    parts_.queue->ack(id);
  } catch (const std::exception& e) {
    engine_.warn_backend(e);
  }
}

// Splits a shared job just marked running into slab tasks when it is a
// streamed job of bits of more than one task; true when it was: its tasks
// are then on the queue for every replica, and it leaves this worker.
bool ReplicatedJobBackend::split(Job& job, const PreparedVoxelJob& prepared) {
  // Only a job planned as runs, streamed: any range of its layers is made alone.
  if (!parts_.slab_tasks || !prepared.streamed || prepared.path != ExecutionPath::runs) return false;
  const std::optional<SlabTaskPlan> plan = plan_slab_tasks(prepared.grid, prepared.slab_layers, parts_.slab_task_bytes);
  if (!plan) return false;
  const std::string id = job.snap.id;
  std::vector<std::string> tasks;
  for (std::int64_t i = 0; i < plan->tasks; ++i) tasks.push_back(slab_task_id(id, i));
  try {
    keep_job_mesh(*store(), id, prepared);
    parts_.slab_tasks->save_plan(id, *plan);
    parts_.queue->split(id, tasks);
    spdlog::info("job {} split into {} slab tasks of {} layers", id, plan->tasks, plan->task_layers);
  } catch (const std::exception& e) {
    // Unsplit: the job's entry goes back, and whoever takes it splits it.
    engine_.warn_backend(e);
    parts_.queue->release(id);
  }
  engine_.forget_running(id);
  job.memory.release();
  return true;
}

void ReplicatedJobBackend::succeeded(Job& job, const JobOutput& output) { engine_.cache_put(job.snap.id, output); }

// A shared job's end: written by compare-and-set (a job run twice ends
// once), its upload dropped, its queue entry acknowledged. A job this
// process stops, or whose end cannot be written, is handed back instead.
void ReplicatedJobBackend::close_out(Job& job, const JobSnapshot& done, bool backend_lost) {
  const std::string id = done.id;
  if (!backend_lost && !job.stopped_by_shutdown) {
    try {
      end(done, {JobState::running}, id);
      return;
    } catch (const BackendUnavailable& e) {
      engine_.warn_backend(e);
    }
  }
  engine_.forget_running(id);
  parts_.queue->release(id);  // another replica runs it again
}

void ReplicatedJobBackend::abandon(const std::string& id) { engine_.forget_running(id); }

// Ends a shared job by compare-and-set (unless another replica or a client
// ended it first) and acknowledges the queue entry `qid` it was ended from:
// the job's own, or one of its slab tasks'. Recorded before it leaves the
// table: a client never sees the job gone or back to "running" from the
// backend after seeing its end here.
void ReplicatedJobBackend::end(JobSnapshot s, std::initializer_list<JobState> from, const std::string& qid) {
  if (s.finished_at.empty()) s.finished_at = format_now();
  if (parts_.records->transition(s, from)) {
    {
      std::lock_guard lock(engine_.mutex);
      ++finished_here_[s.state == JobState::succeeded ? 0 : s.state == JobState::failed ? 1 : 2];
      engine_.announce(s);
    }
    parts_.records->drop_input(s.id);
    if (qid != s.id && parts_.slab_tasks) parts_.slab_tasks->drop_tasks(s.id);
  }
  engine_.forget_running(qid);
  parts_.queue->ack(qid);
  engine_.deliver();
  engine_.finished_cv.notify_all();
}

// The same for a job that failed (or will not run).
void ReplicatedJobBackend::fail(const JobSnapshot& record, JobFailure failure, const std::string& qid) {
  JobSnapshot s = record;
  s.state = JobState::failed;
  s.failure = std::move(failure);
  end(std::move(s), {JobState::queued, JobState::running}, qid);
}

// A job's current snapshot: from the table while it runs here (its live
// progress), else the shared records (its end counts once it is recorded
// there). A synchronous job is not found: it has no routes.
std::optional<JobSnapshot> ReplicatedJobBackend::find(const std::string& id) const {
  {
    std::lock_guard lock(engine_.mutex);
    auto it = engine_.jobs.find(id);
    if (it != engine_.jobs.end()) {
      if (it->second->backend != this) return std::nullopt;
      if (it->second->snap.state == JobState::running) return engine_.snapshot_of(*it->second);
    }
  }
  return parts_.records->load(id);
}

std::vector<JobSnapshot> ReplicatedJobBackend::list(std::size_t offset, std::size_t limit, std::size_t* total,
                                                    const JobFilter& filter) const {
  std::vector<JobSnapshot> page = parts_.records->list(offset, limit, total, filter);
  // Those running here show their live progress.
  std::lock_guard lock(engine_.mutex);
  for (JobSnapshot& s : page)
    if (auto it = engine_.jobs.find(s.id); it != engine_.jobs.end() && it->second->snap.state == JobState::running)
      s = engine_.snapshot_of(*it->second);
  return page;
}

TenantUsage ReplicatedJobBackend::usage(const std::string& tenant) const { return parts_.records->usage(tenant); }

RemoveResult ReplicatedJobBackend::cancel_or_delete(const std::string& id) {
  {
    std::lock_guard lock(engine_.mutex);
    auto it = engine_.jobs.find(id);
    if (it != engine_.jobs.end()) {
      if (it->second->backend != this) return RemoveResult::not_found;
      if (it->second->snap.state == JobState::running) {
        it->second->control.request_cancel();  // running here: the worker records the end
        return RemoveResult::cancelled;
      }
    }
  }
  std::optional<JobSnapshot> record = parts_.records->load(id);
  if (!record) return RemoveResult::not_found;
  if (record->state == JobState::queued) {
    JobSnapshot s = *record;
    s.state = JobState::cancelled;
    s.finished_at = format_now();
    if (parts_.records->transition(s, {JobState::queued})) {
      parts_.queue->cancel(id);
      parts_.records->drop_input(id);
      {
        std::lock_guard lock(engine_.mutex);
        engine_.announce(s);
      }
      engine_.deliver();
      return RemoveResult::cancelled;
    }
    record = parts_.records->load(id);  // taken meanwhile
    if (!record) return RemoveResult::not_found;
  }
  if (record->state == JobState::running) {
    // Whichever replica runs it sees the request within ~100 ms.
    parts_.records->request_cancel(id);
    return RemoveResult::cancelled;
  }
  parts_.store->remove(id);
  engine_.cache.drop_job(id);
  return RemoveResult::deleted;
}

void ReplicatedJobBackend::save_artifact(const std::string& id, const std::string& key, std::string_view bytes) {
  // The store keeps it only while the job's record is there.
  try {
    parts_.store->save_artifact(id, key, bytes);
  } catch (const std::exception& e) {
    spdlog::warn("job {}: cannot keep artifact {}: {}", id, key, e.what());
  }
}

// This replica's jobs (running here, and finished by its workers since it
// started), the shared queue's depth and the replicas alive.
JobCounts ReplicatedJobBackend::counts() const {
  JobCounts c;
  {
    std::lock_guard lock(engine_.mutex);
    for (const auto& [id, job] : engine_.jobs)
      if (job->backend == this && job->snap.state == JobState::running) ++c.running;
    c.succeeded = finished_here_[0];
    c.failed = finished_here_[1];
    c.cancelled = finished_here_[2];
  }
  try {
    c.queue_depth = parts_.queue->depth();
    c.live_replicas = parts_.records->live_replicas();
  } catch (const std::exception& e) {
    engine_.warn_backend(e);
    c.live_replicas = 0;
  }
  return c;
}


bool ReplicatedJobBackend::reachable() const {
  return engine_.backend_ok.load() && steady_ns() - last_contact_ns_.load() < kContactStaleNs;
}

std::size_t ReplicatedJobBackend::expire() {
  // The backend expires records and results itself; its index is pruned.
  try {
    parts_.records->prune();
  } catch (const std::exception& e) {
    engine_.warn_backend(e);
  }
  return 0;
}

void ReplicatedJobBackend::start() {
  // Counted among the live replicas from the start, not a tick later.
  try {
    parts_.records->report_running({});
    last_contact_ns_ = steady_ns();
  } catch (const std::exception& e) {
    engine_.warn_backend(e);
  }
  keeper_ = std::thread([this] { keep(); });
}

// Queued jobs stay in the shared queue, for the other replicas.
void ReplicatedJobBackend::close() { parts_.queue->close(); }

void ReplicatedJobBackend::stop() {
  if (!keeper_.joinable()) return;
  {
    std::lock_guard lock(keeper_mutex_);
    keeper_stop_ = true;
  }
  keeper_wake_.notify_all();
  keeper_.join();
}

// Every ~100 ms, the running jobs' progress and this replica's heartbeat
// out, cancellations in, leases renewed.
void ReplicatedJobBackend::keep() {
  std::unique_lock wait_lock(keeper_mutex_);
  while (!keeper_wake_.wait_for(wait_lock, std::chrono::milliseconds(100), [&] { return keeper_stop_; })) {
    std::vector<SharedJobRecords::RunningReport> running;
    {
      std::lock_guard lock(engine_.mutex);
      for (const auto& [id, job] : engine_.jobs)
        if (job->backend == this && job->snap.state == JobState::running) {
          // A slab task reports for its job, leaving its progress to the
          // tasks' count.
          if (job->task_of.empty())
            running.push_back({id, job->control.progress(), job->control.stage(), job->snap.analyses});
          else
            running.push_back({job->task_of, -1.0, "", nullptr});
        }
    }
    try {
      const std::vector<std::string> cancel = parts_.records->report_running(running);
      engine_.backend_ok = true;
      last_contact_ns_ = steady_ns();
      std::lock_guard lock(engine_.mutex);
      for (const std::string& id : cancel) {
        if (auto it = engine_.jobs.find(id); it != engine_.jobs.end()) it->second->control.request_cancel();
        for (const auto& [key, job] : engine_.jobs)
          if (job->task_of == id) job->control.request_cancel();
      }
    } catch (const std::exception& e) {
      engine_.warn_backend(e);
    }
    try {
      parts_.queue->renew_leases();
    } catch (const std::exception& e) {
      engine_.warn_backend(e);
    }
  }
}

}  // namespace voxd::server
