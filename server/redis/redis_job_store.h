#pragma once
// The job store and the job records on Redis, shared by every replica that
// points at the same Redis (docs/scale-out.md has the key layout and how to
// size Redis's memory). Keys, with PREFIX "voxd:":
//   PREFIX job:ID        hash: record (the job JSON), state, progress,
//                        cancel (asked), entry (its queue entry), hash
//   PREFIX jobs          sorted set: every job by creation time (the list)
//   PREFIX jobs:t:TENANT sorted set: a tenant's jobs by creation time (its
//                        list and its quotas' count); the record's hash
//                        has its tenant and stored bytes beside its state
//   PREFIX tenant-indexes  set: the tenant indexes, for pruning
//   PREFIX hash:SHA256   the succeeded job answering identical submissions
//   PREFIX blob:ID:NAME  hash: gen, chunks, size of one blob (the input, the
//                        volume's RLE, a layer's RLE, an artifact)
//   PREFIX chunk:ID:NAME:GEN:I   its bytes, chunk_bytes at most each
//   PREFIX keys:ID       set: every blob and chunk key of the job, so that
//                        deleting or expiring a job reaches all of them
//   PREFIX replicas      sorted set: replicas by their last heartbeat
//   PREFIX tasks:ID      hash: task index -> voxels, of a split job's tasks
//                        done (server/jobs/slab_tasks.h; the plan is in
//                        job:ID as tasks, task_layers, split; each task's
//                        blocks are the blob "slab:I")
// A blob is written chunk by chunk under a fresh generation and becomes
// visible at once when its manifest is created; a second writer of the same
// blob (a job run twice) finds the manifest there and drops its own chunks,
// so a stored result is written once and never half-written.
#include <atomic>
#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>
#include <functional>
#include <string>
#include <string_view>

#include "server/jobs/job_store.h"
#include "server/jobs/shared_records.h"
#include "server/jobs/slab_tasks.h"
#include "server/redis/redis_client.h"

namespace voxd::server {

struct RedisBackendOptions {
  std::string prefix = "voxd:";
  std::chrono::milliseconds result_ttl = std::chrono::hours(24);
  // Inputs and results of jobs not finished yet: long enough for any queue
  // wait and run; a finished job's keys then take result_ttl.
  std::chrono::milliseconds inflight_ttl = std::chrono::hours(24);
  std::size_t chunk_bytes = std::size_t{8} << 20;  // well under Redis's 512 MB values
  // A job's volume or layer over this many bytes fails (limit-exceeded)
  // instead of filling Redis; 0 = no cap. Admission refuses jobs whose
  // estimate is over it already (JobManagerConfig::max_result_bytes).
  std::uint64_t max_result_bytes = 0;
  std::string replica_id;  // this process, in the heartbeat set
};

class RedisJobStore final : public JobStore, public SharedJobRecords, public SharedSlabTasks {
 public:
  RedisJobStore(std::shared_ptr<RedisPool> pool, RedisBackendOptions options);

  // JobStore
  std::vector<JobSnapshot> load_all() const override { return {}; }  // records are read one by one
  void save(const JobSnapshot& job) const override;
  std::optional<std::string> load_artifact(const std::string& id, const std::string& key) const override;
  void save_artifact(const std::string& id, const std::string& key, std::string_view bytes) const override;
  void save_volume(const std::string& id, const BitVolume& volume) const override;
  std::shared_ptr<const BitVolume> load_volume(const std::string& id) const override;
  void write_volume(const std::string& id, const std::function<void(ByteSink&)>& write) const override;
  std::shared_ptr<const StoredBlob> volume_rle(const std::string& id) const override;
  void save_layer(const std::string& id, const std::string& name, const ValueVolume& values) const override;
  std::shared_ptr<const ValueVolume> load_layer(const std::string& id, const std::string& name) const override;
  void write_layer(const std::string& id, const std::string& name, const ValueVolume& type,
                   const std::function<void(ByteSink&)>& write) const override;
  std::shared_ptr<const StoredBlob> layer_rle(const std::string& id, const std::string& name) const override;
  void share_volume(const std::string& from_id, const std::string& to_id) const override;
  void remove(const std::string& id) const override;
  std::uint64_t free_bytes() const override;
  std::string full_reason() const override { return "Redis is near its maxmemory: its free memory is under --min-free-disk"; }

  // SharedJobRecords
  std::optional<JobSnapshot> load(const std::string& id) const override;
  std::vector<JobSnapshot> list(std::size_t offset, std::size_t limit, std::size_t* total,
                                const JobFilter& filter) const override;
  TenantUsage usage(const std::string& tenant) const override;
  std::uint64_t stored_bytes(const std::string& id) const override;
  bool transition(const JobSnapshot& job, std::initializer_list<JobState> from) const override;
  void save_input(const std::string& id, const std::vector<std::uint8_t>& bytes, const std::string& name_hint) const override;
  std::optional<Input> load_input(const std::string& id) const override;
  void drop_input(const std::string& id) const override;
  std::optional<std::string> succeeded_with_hash(const std::string& hash) const override;
  void request_cancel(const std::string& id) const override;
  std::vector<std::string> report_running(const std::vector<RunningReport>& running) const override;
  bool reachable() const override;
  std::size_t live_replicas() const override;
  void prune() const override;

  // SharedSlabTasks
  void save_plan(const std::string& id, const SlabTaskPlan& plan) const override;
  std::optional<State> state(const std::string& id) const override;
  bool task_done(const std::string& id, std::int64_t index) const override;
  void write_blocks(const std::string& id, std::int64_t index,
                    const std::function<void(ByteSink&)>& write) const override;
  bool read_blocks(const std::string& id, std::int64_t index, ByteSink& sink) const override;
  std::int64_t finish_task(const std::string& id, std::int64_t index, std::uint64_t filled,
                           std::int64_t tasks) const override;
  std::uint64_t filled(const std::string& id) const override;
  void drop_tasks(const std::string& id) const override;

  // A blob as stored, whole; nullopt when there is none (or it expired while
  // being read). Exposed for the tests of the chunking.
  std::optional<std::vector<std::uint8_t>> read_blob(const std::string& id, const std::string& name) const;
  // Writes a blob through `write`; false when an earlier writer's blob is
  // kept instead (or the job is gone). Throws StorageFull past Redis's memory.
  bool write_blob(const std::string& id, const std::string& name, const std::function<void(ByteSink&)>& write) const;

 private:
  std::string key(const std::string& kind, const std::string& id) const { return options_.prefix + kind + ":" + id; }
  std::string tenant_index(const std::string& tenant) const { return options_.prefix + "jobs:t:" + tenant; }
  std::vector<JobSnapshot> load_listed(const std::string& index, const std::vector<std::string>& ids, std::size_t* gone) const;
  std::vector<JobSnapshot> list_matching(const std::string& index, std::size_t offset, std::size_t limit,
                                         std::size_t* total, const JobFilter& filter) const;
  void prune_index(const std::string& index) const;
  std::string blob_key(const std::string& id, const std::string& name) const { return key("blob", id) + ":" + name; }
  // Hands a blob's chunks to `chunk` in order, a few per round trip; false
  // when there is none, or it expired or was deleted while read.
  bool read_chunks(const std::string& id, const std::string& name,
                   const std::function<void(std::string_view)>& chunk) const;
  // A blob read as it is needed (nullptr when there is none).
  std::shared_ptr<const StoredBlob> stored_blob(const std::string& id, const std::string& name) const;
  // A committed blob's manifest: where its chunks are, how many, its size.
  struct BlobManifest {
    std::string chunk_prefix;  // chunk I is chunk_prefix + I
    std::size_t chunks = 0;
    std::uint64_t size = 0;
  };
  std::optional<BlobManifest> manifest(const std::string& id, const std::string& name) const;
  bool write_record(const JobSnapshot& job, const std::string& from) const;

  std::shared_ptr<RedisPool> pool_;
  RedisBackendOptions options_;
  mutable std::atomic<std::int64_t> free_checked_ms_{0};
  mutable std::atomic<std::uint64_t> free_bytes_{UINT64_MAX};
  mutable std::atomic<std::int64_t> heartbeat_ms_{0};
};

}  // namespace voxd::server
