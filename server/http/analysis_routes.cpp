#include "server/http/routes.h"

#include <algorithm>
#include <memory>
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

// Answers from this size up, computed just now, are kept while they are
// sent: a thickness volume's write (400 MB at 512^3) and sync take about
// as long as computing it from the kept map.
constexpr std::size_t kKeepWhileSentFrom = std::size_t{8} << 20;

// The answer's bytes; a large one computed just now is sent while it is
// written, the response holding the bytes and the write until it has been
// sent.
void send_answer(Response& res, AnalysisAnswer answer, const std::string& content_type) {
  if (!answer.keeping) {
    res.set_content(std::move(*answer.bytes), content_type);
    return;
  }
  const std::shared_ptr<const std::string> bytes = std::move(answer.bytes);
  res.set_content_provider(
      bytes->size(), content_type,
      [bytes](std::size_t offset, std::size_t length, httplib::DataSink& sink) {
        return sink.write(bytes->data() + offset, std::min(length, bytes->size() - offset));
      },
      [keeping = std::move(answer.keeping)](bool) {});
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
      AnalysisAnswer answer = analyse_succeeded_job(jobs, job, request, kKeepWhileSentFrom);
      for (const auto& [name, value] : analysis_headers(request, job.grid)) res.set_header(name, value);
      res.set_header("X-Voxd-Cache", answer.kept ? "hit" : "miss");
      send_answer(res, std::move(answer), request.content_type());
    });
  }
}

}  // namespace voxd::server
