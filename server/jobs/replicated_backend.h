#pragma once
// The replicated backend: replicas sharing one queue, one store and the job
// records (server/redis/). A job accepted here is recorded with its upload
// and queued for any replica; a worker that takes one adopts it (record and
// upload read back, prepared again, memory reserved here) and ends it by
// compare-and-set, or hands it back when this process stops or the backend
// goes away. A huge streamed job of bits is split into slab tasks that every
// replica's workers make together (replicated_slab_tasks.cpp). A keeper
// thread reports the running jobs' progress and the replica's heartbeat,
// learns of cancellations asked on other replicas, and renews leases. The
// job table holds only what runs in this process.
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <initializer_list>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <thread>

#include "server/jobs/job_backend.h"
#include "server/jobs/job_queue.h"

namespace voxd::server {

class SharedJobRecords;  // server/jobs/shared_records.h
class SharedSlabTasks;   // server/jobs/slab_tasks.h
struct SlabTaskRef;

struct ReplicatedBackendParts {
  std::shared_ptr<JobQueue> queue;
  std::shared_ptr<JobStore> store;
  std::shared_ptr<SharedJobRecords> records;
  // Set when the backend keeps a huge job's slab tasks
  // (server/jobs/slab_tasks.h): a streamed job of bits whose grid holds more
  // than slab_task_bytes of bits is split into tasks of about that many, so
  // that every replica's workers make it together. Null = never split.
  std::shared_ptr<SharedSlabTasks> slab_tasks;
  std::uint64_t slab_task_bytes = std::uint64_t{1} << 30;
  // A shared job handed out this many times without finishing (its workers'
  // replicas died on it) fails with "redelivery-limit" instead of looping.
  int max_deliveries = 3;
};

// Why a shared job fails without running: handed out too many times, or its
// upload expired before a worker took it.
JobFailure redelivery_failure(int deliveries);
JobFailure input_expired();

// The factory `voxd serve --redis` gives JobManagerConfig::backend.
JobBackendFactory replicated_backend(ReplicatedBackendParts parts);

class ReplicatedJobBackend final : public JobBackend {
 public:
  ReplicatedJobBackend(JobEngine& engine, ReplicatedBackendParts parts);

  JobStore* store() const override { return parts_.store.get(); }
  std::size_t waiting() const override { return parts_.queue->depth(); }
  std::optional<JobSnapshot> earlier_success(const std::string& hash) const override;
  void accept(Admitted admitted) override;

  Next next(std::shared_ptr<Job>& job, PreparedVoxelJob& prepared) override;
  bool record_running(Job& job, const JobSnapshot& running) override;
  void drop_taken(Job& job) override;
  bool split(Job& job, const PreparedVoxelJob& prepared) override;
  void succeeded(Job& job, const JobOutput& output) override;
  void close_out(Job& job, const JobSnapshot& done, bool backend_lost) override;
  void abandon(const std::string& id) override;

  std::optional<JobSnapshot> find(const std::string& id) const override;
  std::vector<JobSnapshot> list(std::size_t offset, std::size_t limit, std::size_t* total,
                                const JobFilter& filter) const override;
  TenantUsage usage(const std::string& tenant) const override;
  RemoveResult cancel_or_delete(const std::string& id) override;
  void save_artifact(const std::string& id, const std::string& key, std::string_view bytes) override;
  JobCounts counts() const override;
  bool reachable() const override;
  std::size_t expire() override;

  void start() override;
  void close() override;
  void stop() override;

 private:
  std::shared_ptr<Job> adopt(const TakenJob& taken, PreparedVoxelJob& prepared);
  bool reserve(Job& job, std::uint64_t need, const std::string& qid);
  void end(JobSnapshot s, std::initializer_list<JobState> from, const std::string& qid);
  void fail(const JobSnapshot& record, JobFailure failure, const std::string& qid);
  void keep();

  // Slab tasks (replicated_slab_tasks.cpp).
  void run_slab_task(const TakenJob& taken, const SlabTaskRef& ref);
  std::optional<PreparedVoxelJob> prepare_again(const std::shared_ptr<Job>& job, const JobSnapshot& record,
                                                const std::string& qid, bool with_analyses);
  void assemble(const std::shared_ptr<Job>& job, const JobSnapshot& record, const std::string& qid,
                std::int64_t tasks);

  JobEngine& engine_;
  ReplicatedBackendParts parts_;
  // Jobs this replica's workers finished since it started (the per-replica
  // counts): succeeded, failed, cancelled; under the table's lock.
  std::uint64_t finished_here_[3] = {0, 0, 0};
  std::thread keeper_;
  std::mutex keeper_mutex_;
  std::condition_variable keeper_wake_;
  bool keeper_stop_ = false;
  // When the keeper last heard from the backend (steady clock, ns): a stalled
  // backend makes the replica not ready within a second or two, without a
  // probe waiting on it.
  std::atomic<std::int64_t> last_contact_ns_{0};
};

}  // namespace voxd::server
