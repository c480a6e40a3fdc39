#pragma once
// A job as the API shows it (proto-schemas/job-status.schema.json): its
// record (server/jobs/job_record.h) with the URLs a client follows (the job,
// its volume, its events, its downloads in every format its mode offers, each
// requested analysis) and its failure's HTTP status.
#include <string>

#include <nlohmann/json.hpp>

#include "api/analysis_request.h"
#include "server/jobs/job.h"

namespace voxd::server {

nlohmann::json job_status_json(const JobSnapshot& job);

// The URL of a request's route for job `id`, canonical query included.
std::string analysis_url(const api::AnalysisRequest& request, const std::string& id);

// One entry of a job's "analyses" (server/jobs/job_analyses.h:
// analyses_status) with the URL that serves it.
nlohmann::json analysis_status_entry(nlohmann::json entry, const std::string& id);

// The HTTP status of a failed job's problem type.
int failure_status(const std::string& type);

}  // namespace voxd::server
