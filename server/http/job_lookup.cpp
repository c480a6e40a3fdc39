#include "server/http/job_lookup.h"

#include "server/http/caller.h"

namespace voxd::server {

const std::string kJobPath = R"(/v1/jobs/([0-9a-f]{32}))";

ProblemError unknown_job(const std::string& id) {
  return ProblemError(make_problem(404, "not-found", "Unknown job", "no job with id " + id + " (it may have expired or been deleted)"));
}

std::optional<JobSnapshot> visible_job(const JobManager& jobs, const std::string& id) {
  std::optional<JobSnapshot> job = jobs.get(id);
  if (job && !current_caller().sees(*job)) job.reset();
  return job;
}

JobSnapshot known_job(const JobManager& jobs, const std::string& id) {
  std::optional<JobSnapshot> job = visible_job(jobs, id);
  if (!job) throw unknown_job(id);
  return std::move(*job);
}

JobSnapshot succeeded_job(JobManager& jobs, const std::string& id, const std::string& result, const std::string& exists) {
  const std::optional<JobSnapshot> job = visible_job(jobs, id);
  if (!job) throw unknown_job(id);
  if (job->state != JobState::succeeded)
    throw ProblemError(make_problem(409, "job-not-finished", "The job has no " + result + " yet",
                                    std::string("the job is ") + to_string(job->state) + "; " + exists + " once it has succeeded"));
  return *job;
}

}  // namespace voxd::server
