#pragma once
// What replicas sharing one backend must agree on beyond the queue and the
// blobs (job_queue.h, job_store.h): the job records themselves. In the
// embedded mode the job engine's own table is the truth; with a shared
// backend (server/redis/) the table is there, every replica reads and
// changes it through these calls, and each state change is a compare-and-set
// so that two replicas never both move a job on.
#include <cstdint>
#include <initializer_list>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "server/jobs/job.h"

namespace voxd::server {

class SharedJobRecords {
 public:
  virtual ~SharedJobRecords() = default;

  // A job's record, with the live progress of a running one; nullopt when
  // unknown, deleted or expired.
  virtual std::optional<JobSnapshot> load(const std::string& id) const = 0;
  // Newest first, those `filter` matches; `total` receives their number.
  virtual std::vector<JobSnapshot> list(std::size_t offset, std::size_t limit, std::size_t* total,
                                        const JobFilter& filter) const = 0;
  // What a tenant's jobs hold now.
  virtual TenantUsage usage(const std::string& tenant) const = 0;
  // Writes `job` only when its stored state is one of `from`. False when it
  // is not (another replica or a client moved it on) or the job is gone. A
  // finished record starts the job's expiry (result_ttl), and a succeeded
  // one becomes the answer to identical submissions.
  virtual bool transition(const JobSnapshot& job, std::initializer_list<JobState> from) const = 0;

  // The upload a job is made from, kept until the job ends (or expires) so
  // that any replica can run it. Throws StorageFull when it does not fit.
  virtual void save_input(const std::string& id, const std::vector<std::uint8_t>& bytes,
                          const std::string& name_hint) const = 0;
  struct Input {
    std::vector<std::uint8_t> bytes;
    std::string name_hint;
  };
  virtual std::optional<Input> load_input(const std::string& id) const = 0;
  virtual void drop_input(const std::string& id) const = 0;

  // The id of a succeeded job with this content hash, if one is kept.
  virtual std::optional<std::string> succeeded_with_hash(const std::string& hash) const = 0;

  // Asks whichever replica runs the job to stop it (it polls, ~100 ms).
  virtual void request_cancel(const std::string& id) const = 0;
  // This replica's running jobs, reported every ~100 ms: the progress and
  // live state others show (JobSnapshot's progress, stage and analyses as
  // each becomes ready), the replica's heartbeat. Returns the ids whose
  // cancellation was asked (or whose record was deleted).
  struct RunningReport {
    std::string id;
    double progress = -1.0;  // negative: left as it is (a job whose slab tasks run here)
    std::string stage;       // empty with a negative progress: left as it is
    nlohmann::json analyses;  // null: left as it is
  };
  virtual std::vector<std::string> report_running(const std::vector<RunningReport>& running) const = 0;

  // Whether the backend answers now.
  virtual bool reachable() const = 0;
  // Replicas that reported in the last few seconds.
  virtual std::size_t live_replicas() const = 0;
  // Drops the index entries of jobs the backend expired.
  virtual void prune() const = 0;
};

}  // namespace voxd::server
