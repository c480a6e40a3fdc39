#pragma once
// Finding the job a /v1/jobs/{id}/… route names, with the problems every such
// route answers alike: 404 for a job that is not (or no longer) there or is
// another tenant's (server/http/caller.h: the same answer, so that an id
// tells nothing), 409 for one that has not succeeded yet. Every job route
// finds its job here.
#include <optional>
#include <string>

#include "server/http/problem.h"
#include "server/jobs/job_manager.h"

namespace voxd::server {

// The /v1/jobs/{id} pattern; the id is match 1.
extern const std::string kJobPath;

ProblemError unknown_job(const std::string& id);

// The job, when the caller may see it; else nothing, as for an unknown one.
std::optional<JobSnapshot> visible_job(const JobManager& jobs, const std::string& id);
// The same, or the 404.
JobSnapshot known_job(const JobManager& jobs, const std::string& id);

// The job, succeeded. `result` names what the route serves ("volume"), for the
// 409's title; `exists` completes "…; <exists> once it has succeeded".
JobSnapshot succeeded_job(JobManager& jobs, const std::string& id, const std::string& result, const std::string& exists);

}  // namespace voxd::server
