#include "server/http/routes.h"

#include <optional>
#include <string>

#include <httplib.h>

#include "api/analysis_request.h"
#include "server/http/job_analysis_answer.h"
#include "server/http/analysis_headers.h"
#include "server/http/job_lookup.h"
#include "server/http/route_table.h"
#include "server/jobs/job_analyses.h"
#include "server/jobs/job_manager.h"

namespace voxd::server {
namespace {

using httplib::Request;
using httplib::Response;

struct KeptAnalysis {
  Grid grid;
  std::string bytes;
};

// The kept result of a request a running job's JSON asked for and its
// worker has made ready; nothing for any other job or request.
std::optional<KeptAnalysis> ready_while_running(JobManager& jobs, const std::string& id,
                                                const api::AnalysisRequest& request) {
  const auto job = visible_job(jobs, id);
  if (!job || job->state != JobState::running || !job->analyses.is_array()) return std::nullopt;
  for (const auto& entry : job->analyses) {
    if (api::to_json(request) != entry.value("request", nlohmann::json()) || entry.value("state", "") != "ready") continue;
    if (auto bytes = jobs.load_artifact(id, request.artifact_key())) return KeptAnalysis{job->grid, std::move(*bytes)};
  }
  return std::nullopt;
}

}  // namespace

void install_analysis_routes(RouteTable& routes, JobManager& jobs) {
  for (const auto& [kind, name] : api::kAnalysisKindNames) {
    routes.get(kJobPath + "/" + to_string(kind), [&jobs, kind](const Request& req, Response& res) {
      const std::string id = req.matches[1];
      const api::AnalysisRequest request = analysis_request_of(kind, {req.params.begin(), req.params.end()});
      // One the job JSON asked for is served as soon as it is ready, while
      // the job still runs (its event stream says when).
      if (auto kept = ready_while_running(jobs, id, request)) {
        for (const auto& [name, value] : analysis_headers(request, kept->grid)) res.set_header(name, value);
        res.set_header("X-Voxd-Cache", "hit");
        res.set_content(std::move(kept->bytes), request.content_type());
        return;
      }
      const JobSnapshot job = succeeded_job(jobs, id, "volume", "its analyses exist");
      AnalysisResult result = analyse_succeeded_job(jobs, job, request);  // its bytes are moved into the answer
      for (const auto& [name, value] : analysis_headers(request, job.grid)) res.set_header(name, value);
      res.set_header("X-Voxd-Cache", result.kept ? "hit" : "miss");
      res.set_content(std::move(result.bytes), request.content_type());
    });
  }
}

}  // namespace voxd::server
