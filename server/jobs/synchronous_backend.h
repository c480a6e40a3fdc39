#pragma once
// The backend of a synchronous job (POST /v1/voxelize): it waits in the
// in-process queue like any job there, so it cannot starve the others, but
// it has no store. Its record is written nowhere, no query finds it, it is
// never streamed nor answered from an earlier job, and its volumes go to the
// caller waiting in JobManager::run_sync.
#include "server/jobs/job_backend.h"

namespace voxd::server {

class SynchronousJobBackend final : public JobBackend {
 public:
  explicit SynchronousJobBackend(JobEngine& engine) : engine_(engine) {}

  JobStore* store() const override { return nullptr; }
  std::size_t waiting() const override;
  void accept(Admitted admitted) override;
  // Its jobs are taken from the in-process queue by the service's backend.
  Next next(std::shared_ptr<Job>&, PreparedVoxelJob&) override { return Next::stopped; }
  bool record_running(Job&, const JobSnapshot&) override { return true; }
  void drop_taken(Job& job) override;
  void succeeded(Job& job, const JobOutput& output) override;
  void ended(const JobSnapshot& done) override;
  void close_out(Job& job, const JobSnapshot& done, bool backend_lost) override;

 private:
  JobEngine& engine_;
};

}  // namespace voxd::server
