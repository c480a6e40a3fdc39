#include "server/http/analysis_routes.h"

#include <string>
#include <vector>

#include <httplib.h>

#include "api/analysis_request.h"
#include "api/param_error.h"
#include "server/http/problem.h"
#include "server/jobs/job_analyses.h"
#include "server/jobs/job_manager.h"

namespace voxd::server {
namespace {

using httplib::Request;
using httplib::Response;

struct FinishedJob {
  JobSnapshot snapshot;
  JobOutput output;
};

FinishedJob finished_job(JobManager& jobs, const std::string& id) {
  auto unknown = [&] {
    return ProblemError(make_problem(404, "not-found", "Unknown job", "no job with id " + id + " (it may have expired or been deleted)"));
  };
  const auto job = jobs.get(id);
  if (!job) throw unknown();
  if (job->state != JobState::succeeded)
    throw ProblemError(make_problem(409, "job-not-finished", "The job has no volume yet",
                                    std::string("the job is ") + to_string(job->state) + "; its analyses exist once it has succeeded"));
  JobOutput output{jobs.volume(id), jobs.values(id), {}};
  if (!output.solid || (job->has_value_volume() && !output.values)) throw unknown();
  return {*job, std::move(output)};
}

ProblemError invalid_query(const std::string& detail) {
  return ProblemError(make_problem(400, "invalid-query", "Invalid query parameter", detail));
}

// The query as request fields; every problem goes into one 400 answer.
api::AnalysisRequest request_of(api::AnalysisKind kind, const Request& req) {
  api::Fields fields(req.params.begin(), req.params.end());
  try {
    return api::parse_analysis_request(kind, fields, "");
  } catch (const api::InvalidParams& e) {
    std::string detail;
    for (const auto& f : e.errors()) detail += (detail.empty() ? "" : "; ") + f.path.substr(1) + " " + f.message;
    throw invalid_query(detail);
  }
}

}  // namespace

std::vector<std::string> install_analysis_routes(httplib::Server& server, JobManager& jobs, const std::string& job_path,
                                                 const Guard& guarded) {
  std::vector<std::string> patterns;
  for (api::AnalysisKind kind : {api::AnalysisKind::analysis, api::AnalysisKind::radiography, api::AnalysisKind::section,
                                 api::AnalysisKind::preview, api::AnalysisKind::thickness}) {
    const std::string pattern = job_path + "/" + to_string(kind);
    patterns.push_back(pattern);
    server.Get(pattern, guarded([&jobs, kind](const Request& req, Response& res) {
      const std::string id = req.matches[1];
      const api::AnalysisRequest request = request_of(kind, req);
      const FinishedJob job = finished_job(jobs, id);
      // Computing (or even serving a kept result, read whole) takes memory
      // beside the job's volumes: held from the budget meanwhile.
      const MemoryBudget::Reservation memory =
          jobs.reserve_memory(estimate_analysis_memory(request, job.snapshot.grid), "this analysis");
      AnalysisResult result;
      try {
        result = job_analysis(request, job.snapshot, job.output, artifacts_of(jobs, id));
      } catch (const AnalysisRejected& e) {
        throw invalid_query(e.what());
      }
      for (const auto& [name, value] : analysis_headers(request, job.snapshot.grid)) res.set_header(name, value);
      res.set_header("X-Voxd-Cache", result.kept ? "hit" : "miss");
      res.set_content(std::move(result.bytes), request.content_type());
    }));
  }
  return patterns;
}

}  // namespace voxd::server
