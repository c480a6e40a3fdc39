#include "server/http/routes.h"

#include <string>
#include <vector>

#include <httplib.h>

#include "api/analysis_request.h"
#include "api/param_error.h"
#include "server/http/job_lookup.h"
#include "server/http/problem.h"
#include "server/http/route_table.h"
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
  JobSnapshot job = succeeded_job(jobs, id, "volume", "its analyses exist");
  JobOutput output{jobs.volume(id), jobs.values(id), {}};
  if (!output.solid || (job.has_value_volume() && !output.values)) throw unknown_job(id);
  return {std::move(job), std::move(output)};
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

void install_analysis_routes(RouteTable& routes, JobManager& jobs) {
  for (api::AnalysisKind kind : {api::AnalysisKind::analysis, api::AnalysisKind::radiography, api::AnalysisKind::section,
                                 api::AnalysisKind::preview, api::AnalysisKind::thickness}) {
    routes.get(kJobPath + "/" + to_string(kind), [&jobs, kind](const Request& req, Response& res) {
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
    });
  }
}

}  // namespace voxd::server
