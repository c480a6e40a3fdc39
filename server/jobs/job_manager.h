#pragma once
// The service's job engine: the job table (states, progress, the identical-
// submission index) and the worker loop, over parts with seams: a queue
// (server/jobs/job_queue.h), a store of records and result blobs
// (job_store.h), a volume cache (volume_cache.h), event delivery
// (job_events.h) and memory admission (memory_budget.h). No HTTP here:
// server/http turns requests into these calls and these results into
// responses.
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "server/jobs/job.h"
#include "server/jobs/job_backend.h"
#include "server/jobs/memory_budget.h"

namespace voxd::server {

struct JobManagerConfig {
  // The service's backend: where its jobs wait, are kept and end
  // (server/jobs/job_backend.h). Null: the embedded one (an in-process
  // queue of queue_size, the data directory); replicas sharing one Redis
  // pass replicated_backend(...) (server/jobs/replicated_backend.h).
  // Synchronous jobs (run_sync) always run in this process, stored nowhere.
  JobBackendFactory backend;
  // Jobs whose volumes (uncompressed) would be over this many bytes are
  // refused at admission (422); 0 = no cap. For a backend that keeps results
  // in memory (Redis), so that one job cannot fill it.
  std::uint64_t max_result_bytes = 0;
  int workers = 0;              // 0 = hardware concurrency
  std::size_t queue_size = 64;  // jobs waiting (not running) at most
  std::filesystem::path data_dir = "voxd-data";
  JobLimits limits;
  std::uint64_t max_job_memory = std::uint64_t{4} << 30;  // bytes of volumes one job may need
  // Bytes all queued and running jobs, decodes and analyses may take at once
  // (server/jobs/memory_budget.h); 0 = 60% of the machine's or container's memory.
  std::uint64_t memory_budget = 0;
  // Submissions are refused (507) and /readyz is not ready while the data
  // directory's disk has less than this free.
  std::uint64_t min_free_disk = std::uint64_t{64} << 20;
  std::chrono::seconds result_ttl{24 * 3600};            // finished jobs expire after this
  // Called (from worker or submitting threads, never under the table's lock)
  // on every state change, for logs and metrics.
  std::function<void(const JobSnapshot&)> on_state_change;
};

class JobManager {
 public:
  // Opens (creates) the store under data_dir; jobs recorded as queued or
  // running by a previous process become failed with type "interrupted";
  // finished results are kept. Starts the workers.
  explicit JobManager(JobManagerConfig config);
  ~JobManager();  // shutdown(0s) if not done yet
  JobManager(const JobManager&) = delete;
  JobManager& operator=(const JobManager&) = delete;

  // Runs prepare_voxel_job on the calling thread (cheap: decode + grid), so bad
  // meshes and oversized grids throw voxd::Error right away, then checks the
  // memory estimate against max_job_memory (Error limit_exceeded) and queues
  // the job. An identical earlier submission (same mesh bytes and canonical
  // params) that succeeded and has not expired is answered from its result:
  // the new job is created already succeeded with cached = true.
  // `labels` say whose it is and how its owner knows it (job.h); an
  // identical earlier submission answers only one of the same tenant.
  // Throws QueueFull, NotAccepting, voxd::Error, api::InvalidParams.
  JobSnapshot submit(std::vector<std::uint8_t> mesh_bytes, const std::string& name_hint,
                     const nlohmann::json& params_json, const JobLabels& labels = {});

  std::optional<JobSnapshot> get(const std::string& id) const;

  // Waits until a job changed state or had an analysis made ready since
  // `seen` (a value this returned before; 0 at first), or until `timeout`;
  // returns the value to pass next time. Progress moves without a change,
  // and so do jobs other replicas change: watchers poll get() as well.
  std::uint64_t wait_for_change(std::uint64_t seen, std::chrono::milliseconds timeout) const;

  // Newest first, those `filter` matches. `total` receives their number.
  std::vector<JobSnapshot> list(std::size_t offset, std::size_t limit, std::size_t* total,
                                const JobFilter& filter = {}) const;
  // What a tenant's jobs hold now (queued, running, stored bytes), for its quotas.
  TenantUsage usage(const std::string& tenant) const;

  using RemoveResult = server::RemoveResult;
  // Queued or running: cancel (a running voxelization stops within ~50 ms and
  // the job ends cancelled). Finished: delete the job and its files.
  RemoveResult cancel_or_delete(const std::string& id);

  // The result volume of a succeeded job (loaded from the store if not in
  // memory); nullptr if the job is unknown or not succeeded.
  std::shared_ptr<const BitVolume> volume(const std::string& id);
  // A succeeded job's volume as stored (its RLE), to be read slab by slab:
  // how a streamed job's volume is served and analysed. nullptr if the job
  // is unknown or not succeeded.
  std::shared_ptr<const StoredBlob> volume_rle(const std::string& id);
  // The same for a streamed job's values (nullptr for a job without values).
  std::shared_ptr<const StoredBlob> values_rle(const std::string& id);
  // A succeeded value job's values; nullptr for other jobs.
  std::shared_ptr<const ValueVolume> values(const std::string& id);
  // A succeeded job's volume of values by name: "values" or one of its
  // mode's stored layers; nullptr when it has none of that name.
  std::shared_ptr<const ValueVolume> layer(const std::string& id, const std::string& name);

  // Submits and waits for the result (POST /v1/voxelize). The job goes
  // through the same queue, so it cannot starve asynchronous jobs, but it is
  // never stored. Returns an empty output (solid null) when the job did not
  // succeed; `snapshot` then holds its failure. Throws like submit().
  // `max_voxels` (0 = none) is an extra, smaller grid limit for this call.
  // `abandoned`, asked every 100 ms while the job waits or runs, cancels it
  // when it answers true (the caller's client went away).
  JobOutput run_sync(std::vector<std::uint8_t> mesh_bytes, const std::string& name_hint,
                     const nlohmann::json& params_json, JobSnapshot* snapshot, std::uint64_t max_voxels = 0,
                     const std::function<bool()>& abandoned = {});

  // Derived results of a finished job (analysis JSON, images), kept beside
  // its volume so they are computed once and expire with it. `key` is a file
  // name made by the caller from the request ([A-Za-z0-9._-]).
  std::optional<std::string> load_artifact(const std::string& id, const std::string& key) const;
  bool load_artifact_into(const std::string& id, const std::string& key, std::span<char> out) const;
  void save_artifact(const std::string& id, const std::string& key, std::string_view bytes);

  JobCounts counts() const;
  bool accepting() const;

  // Holds `bytes` of the memory budget for work outside a job (an analysis
  // asked for over HTTP) until the reservation is dropped. Throws MemoryBusy
  // when it does not fit now, voxd::Error limit_exceeded when it never can.
  MemoryBudget::Reservation reserve_memory(std::uint64_t bytes, const std::string& what);
  std::uint64_t memory_budget() const;
  // The most memory one job's volumes (and an analysis of them) may take.
  std::uint64_t max_job_memory() const;
  // Why the store takes no new jobs (its free space is under
  // --min-free-disk, or it cannot be asked), or nothing when it takes them.
  std::optional<std::string> storage_full() const;
  // Whether the shared backend answered lately (always true embedded).
  bool backend_ok() const;
  std::uint64_t memory_in_use() const;

  // Stops accepting; lets running jobs finish for up to `deadline`, then
  // cancels them (recorded as failed/interrupted so a restart reports them);
  // queued jobs are recorded as failed/interrupted. Joins the workers.
  void shutdown(std::chrono::seconds deadline);

  // Removes jobs finished longer than result_ttl ago (also runs periodically).
  std::size_t expire_now();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace voxd::server
