#pragma once
// What the parts of the job engine share, inside the engine only (the
// service talks to JobManager, server/jobs/job_manager.h): the job table
// (every job this process holds, each with the backend it belongs to), its
// lock and change count, the in-process queue, the memory budget, the
// volume cache and event delivery; admission (job_admission.cpp) and the
// worker (job_worker.cpp) as functions over them. Which backend a job
// belongs to (job_backend.h) decides where it waits, where it is kept and how
// its end is recorded; nothing here asks how the service is set up.
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

#include <nlohmann/json.hpp>

#include "server/pipeline/job_pipeline.h"
#include "server/jobs/job.h"
#include "server/jobs/job_backend.h"
#include "server/jobs/job_events.h"
#include "server/jobs/job_manager.h"
#include "server/jobs/job_queue.h"
#include "server/jobs/memory_budget.h"
#include "server/jobs/volume_cache.h"
#include "voxd/error.h"
#include "voxd/progress.h"

namespace voxd::server {

class JobStore;    // server/jobs/job_store.h

// One job this process holds: a job it keeps (embedded), one it runs
// (taken from a shared queue, or one slab task of such a job), or a
// synchronous one while its caller waits.
struct Job {
  JobSnapshot snap;
  // Where the job waits, is kept and ends: never null.
  JobBackend* backend = nullptr;
  std::optional<PreparedVoxelJob> prepared;  // until a worker takes it
  JobControl control;
  // A slab task of a shared job split over the replicas: that job's id (the
  // task's own is its queue id, its key in the table).
  std::string task_of;
  JobOutput result;  // a synchronous job's volumes, for its caller
  bool stopped_by_shutdown = false;  // cancelled because the service stops
  // The job's share of the memory budget (its decoded mesh, volumes and
  // analyses), from acceptance (or, taken from a shared queue, from adoption)
  // until it ends.
  MemoryBudget::Reservation memory;
  // Serializes this job's store writes with its removal: a worker writing the
  // final record just after a client deleted the finished job must not bring
  // it back on disk (and after a restart, in the API).
  std::mutex store_mutex;
  bool removed = false;  // guarded by store_mutex
};

std::string new_job_id();
std::string format_now();
JobFailure interrupted(const char* was);
// The failure a job records for an engine error: the error table's slug and,
// for errors a client can act on, the message.
JobFailure failure_of(const Error& e);

class JobEngine {
 public:
  explicit JobEngine(JobManagerConfig config);

  JobManagerConfig config;
  // Jobs that run in this process wait here: synchronous ones always, and
  // every job of a backend that has no queue of its own (embedded).
  std::shared_ptr<JobQueue> local_queue;
  JobEvents events;
  VolumeCache cache{std::size_t{1} << 30};
  MemoryBudget budget;
  int engine_threads = 0;

  // The job table: every job this process holds, by id, and every Job's
  // snap, under one lock.
  mutable std::mutex mutex;
  std::unordered_map<std::string, std::shared_ptr<Job>> jobs;
  std::condition_variable finished_cv;  // synchronous callers and shutdown wait here
  // Every state change and every analysis made ready counts one, for the
  // event streams (wait_for_change); progress moves without counting.
  std::uint64_t changes = 0;
  std::condition_variable changed_cv;
  bool accepting = true;
  double recent_job_seconds = 1.0;  // moving average, for Retry-After

  // Caller holds mutex: the table's order. Wakes whoever waits for a change.
  void announce(const JobSnapshot& s);
  void note_change();                       // caller holds mutex
  void deliver() { events.deliver(); }      // caller holds no lock
  JobSnapshot snapshot_of(const Job& job) const;  // caller holds mutex
  // Requires no lock: drops a job from the table.
  void forget_running(const std::string& id);

  // A shared backend that stopped answering: logged once every 10 s.
  void warn_backend(const std::exception& e);
  std::atomic<bool> backend_ok{true};

  // The limits a job is prepared under: a job that would not fit the per-job
  // memory whole streams where it can; a job whose backend keeps no store
  // (synchronous) is never stored, so never streamed.
  JobLimits job_limits(bool stored) const;
  // The most memory the job's analyses take beside its volumes.
  std::uint64_t analyses_memory(const api::JobParams& params, const PreparedVoxelJob& prepared) const;
  // The volumes of a succeeded job in the cache (a streamed one's are on
  // disk only).
  void cache_put(const std::string& id, const JobOutput& output);
  // The analyses the job JSON asked for, computed now with the job's
  // backend's store and kept as the routes would keep them. A request the
  // grid cannot answer fails alone; cancellation stops the job.
  nlohmann::json prepare_analyses(Job& job, JobStore& store, const std::vector<api::AnalysisRequest>& requests,
                                  const VoxelJobResult& r, const JobOutput& output);
  // Seconds a client refused for a full queue of `waiting` jobs should wait.
  int retry_after(std::size_t waiting) const;
  // The refusal of a submission to a queue of `waiting` jobs (HTTP 429).
  QueueFull queue_full(std::size_t waiting) const;
  std::size_t worker_count = 1;

  // Admission (job_admission.cpp): parses and checks the submission, decodes
  // and prepares the job and hands it to `backend`. An identical earlier
  // submission the backend can answer from is answered: `cached_out` is then
  // set and null is returned. Throws like JobManager::submit.
  std::shared_ptr<Job> admit(JobBackend& backend, std::vector<std::uint8_t>& mesh_bytes, const std::string& name_hint,
                             const JobLabels& labels,
                             const nlohmann::json& params_json, JobSnapshot* cached_out, std::uint64_t max_voxels);

  // How a backend whose jobs run where they were accepted (embedded,
  // synchronous) queues one: the upload freed, the job's memory reserved,
  // its record written to `store` (if any) before a worker can see it, then
  // into the table and the in-process queue. Throws QueueFull, NotAccepting,
  // MemoryBusy, StorageFull.
  void enqueue_local(JobBackend::Admitted& admitted, JobStore* store);

  // The worker (job_worker.cpp): takes jobs from `backend` (and the
  // in-process queue) until both are closed, and runs each.
  void work(JobBackend& backend);
  // A job in the table, taken from the in-process queue, with its prepared
  // job moved out; null when it was cancelled while waiting (then acked).
  std::shared_ptr<Job> take_local(const std::string& id, PreparedVoxelJob& prepared);
  // A job's record once it succeeded with `r`.
  static void record_success(JobSnapshot& s, const VoxelJobResult& r, std::optional<nlohmann::json> analyses_done);

 private:
  bool mark_running(Job& job);
  void run(Job& job, PreparedVoxelJob prepared);
  std::atomic<std::int64_t> backend_warned_at_{0};
};

}  // namespace voxd::server
