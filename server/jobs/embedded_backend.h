#pragma once
// The embedded backend: one process keeps every job it accepted, in the job
// table and the data directory (LocalJobStore), and runs them from the
// in-process queue. It answers identical submissions from the table's index
// of succeeded jobs by content hash, and at start reports the jobs a
// previous process left queued or running as interrupted.
#include <memory>
#include <string>
#include <string_view>
#include <unordered_map>

#include "server/jobs/job_backend.h"

namespace voxd::server {

class EmbeddedJobBackend final : public JobBackend {
 public:
  // Opens (creates) the store under the engine's data directory and reads
  // the jobs kept there into the table.
  explicit EmbeddedJobBackend(JobEngine& engine);

  JobStore* store() const override { return store_.get(); }
  std::size_t waiting() const override;
  std::optional<JobSnapshot> earlier_success(const std::string& hash) const override;
  void keep_answered(const JobSnapshot& s) override;
  void accept(Admitted admitted) override;

  Next next(std::shared_ptr<Job>& job, PreparedVoxelJob& prepared) override;
  bool record_running(Job& job, const JobSnapshot& running) override;
  void drop_taken(Job& job) override;
  void succeeded(Job& job, const JobOutput& output) override;
  void discard_partial(Job& job) override;
  void ended(const JobSnapshot& done) override;
  void close_out(Job& job, const JobSnapshot& done, bool backend_lost) override;

  std::optional<JobSnapshot> find(const std::string& id) const override;
  std::vector<JobSnapshot> list(std::size_t offset, std::size_t limit, std::size_t* total,
                                const JobFilter& filter) const override;
  TenantUsage usage(const std::string& tenant) const override;
  RemoveResult cancel_or_delete(const std::string& id) override;
  void save_artifact(const std::string& id, const std::string& key, std::string_view bytes) override;
  JobCounts counts() const override;
  std::size_t expire() override;

 private:
  void persist(Job& job, const JobSnapshot& s) const;
  void remove_from_store(Job& job) const;
  void forget(const std::string& id);  // caller holds the table's lock

  JobEngine& engine_;
  std::shared_ptr<JobStore> store_;
  std::unordered_map<std::string, std::string> succeeded_by_hash_;  // content hash -> job id; under the table's lock
};

}  // namespace voxd::server
