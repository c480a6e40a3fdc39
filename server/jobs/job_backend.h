#pragma once
// Where jobs wait, where they are kept and how their ends are recorded: the
// seam between the job engine (admission, the worker, the table:
// job_engine.h) and how the service is set up. Three implementations:
//   - EmbeddedJobBackend (embedded_backend.h): one process, the in-process
//     queue, records and results in the data directory;
//   - ReplicatedJobBackend (replicated_backend.h): replicas sharing one
//     queue, one store and the job records (server/redis/), each state
//     change a compare-and-set;
//   - SynchronousJobBackend (synchronous_backend.h): a POST /v1/voxelize
//     job, in this process, stored nowhere and found by no query; its
//     caller waits for the volumes.
// `voxd serve` picks the service's backend once (JobManagerConfig::backend);
// every service also has a synchronous one. Every Job in the table names
// its backend, and the engine asks it, never a flag, what to do.
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "server/pipeline/job_pipeline.h"
#include "server/jobs/job.h"
#include "server/jobs/memory_budget.h"

namespace voxd::server {

class JobEngine;  // server/jobs/job_engine.h
class JobStore;   // server/jobs/job_store.h
struct Job;

class JobBackend {
 public:
  virtual ~JobBackend() = default;

  // Where the backend keeps records, results and artifacts; null for one
  // that keeps nothing (synchronous jobs: no identical-submission answer, no
  // mesh report, never streamed).
  virtual JobStore* store() const = 0;

  // --- Admission (JobEngine::admit)
  // Jobs waiting for a worker, against the queue's capacity.
  virtual std::size_t waiting() const = 0;
  // The record of a succeeded job with this content hash that can answer an
  // identical submission.
  virtual std::optional<JobSnapshot> earlier_success(const std::string& hash) const {
    (void)hash;
    return std::nullopt;
  }
  // A job answered from an earlier one's result, recorded already: shown by
  // the queries from now on.
  virtual void keep_answered(const JobSnapshot& s) { (void)s; }
  // Queues the admitted job (its snap filled in, queued), prepared as
  // `prepared` from `mesh_bytes`; `decoding` holds the upload's share of the
  // memory budget and `memory` is what the job needs while it runs.
  // Throws QueueFull, NotAccepting, StorageFull, BackendUnavailable.
  struct Admitted {
    std::shared_ptr<Job> job;
    PreparedVoxelJob prepared;
    std::vector<std::uint8_t>& mesh_bytes;
    const std::string& name_hint;
    MemoryBudget::Reservation& decoding;
    std::uint64_t memory = 0;
  };
  virtual void accept(Admitted admitted) = 0;

  // --- The worker (JobEngine::work)
  enum class Next { job, none, stopped };
  // The next job for a worker, with its prepared job moved out: from the
  // in-process queue (JobEngine::take_local) or this backend's own. `stopped`
  // once the service stops and nothing is left to take.
  virtual Next next(std::shared_ptr<Job>& job, PreparedVoxelJob& prepared) = 0;
  // Writes the record of a job a worker starts (`running`, under the job's
  // store_mutex); false when the job was moved on meanwhile (cancelled).
  virtual bool record_running(Job& job, const JobSnapshot& running) = 0;
  // A job taken but not run (cancelled meanwhile, or its record could not be
  // written): its queue entry ended.
  virtual void drop_taken(Job& job) = 0;
  // Spreads a job just marked running over the replicas instead of running
  // it here; true when it did (it then leaves this worker).
  virtual bool split(Job& job, const PreparedVoxelJob& prepared) {
    (void)job;
    (void)prepared;
    return false;
  }
  // Under the table's lock: the job succeeded with `output` (its record says so).
  virtual void succeeded(Job& job, const JobOutput& output) = 0;
  // A job whose result could not be stored leaves nothing half-written.
  virtual void discard_partial(Job& job) { (void)job; }
  // Under the table's lock: the job's end as the table has it.
  virtual void ended(const JobSnapshot& done) { (void)done; }
  // Then, with no lock held: its end recorded and its queue entry ended, or,
  // when `backend_lost` or the service stops, handed back for another replica.
  virtual void close_out(Job& job, const JobSnapshot& done, bool backend_lost) = 0;
  // The bookkeeping after running the job failed (not the job itself: the
  // backend went away mid-way).
  virtual void abandon(const std::string& id) { (void)id; }

  // --- Queries (JobManager). A backend without a store finds nothing.
  virtual std::optional<JobSnapshot> find(const std::string& id) const {
    (void)id;
    return std::nullopt;
  }
  virtual std::vector<JobSnapshot> list(std::size_t offset, std::size_t limit, std::size_t* total,
                                        const JobFilter& filter) const {
    (void)offset;
    (void)limit;
    (void)filter;
    if (total) *total = 0;
    return {};
  }
  virtual TenantUsage usage(const std::string& tenant) const {
    (void)tenant;
    return {};
  }
  virtual RemoveResult cancel_or_delete(const std::string& id) {
    (void)id;
    return RemoveResult::not_found;
  }
  virtual void save_artifact(const std::string& id, const std::string& key, std::string_view bytes) {
    (void)id;
    (void)key;
    (void)bytes;
  }
  virtual JobCounts counts() const { return {}; }
  // Whether the backend answered lately.
  virtual bool reachable() const { return true; }
  // Removes (or lets the backend remove) jobs past their time.
  virtual std::size_t expire() { return 0; }

  // --- Lifetime
  virtual void start() {}  // once the workers run
  // Under the table's lock, when the service stops: takes no more.
  virtual void close() {}
  virtual void stop() {}  // once the workers are joined
};

// How JobManager makes its service's backend (JobManagerConfig::backend).
using JobBackendFactory = std::function<std::unique_ptr<JobBackend>(JobEngine&)>;

}  // namespace voxd::server
