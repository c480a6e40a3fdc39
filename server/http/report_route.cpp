// GET /v1/jobs/{id}/report: the job's report as one self-contained HTML
// file (server/reports/job_report_html.h), made from the analyses the API
// serves: the analysis report with the job's own min and max wall (or the
// query's), and previews painted by wall thickness from three sides.
#include "server/http/routes.h"

#include <cctype>

#include <httplib.h>

#include "api/analysis_request.h"
#include "server/http/job_analysis_answer.h"
#include "server/http/job_lookup.h"
#include "server/http/job_status.h"
#include "server/http/problem.h"
#include "server/http/route_table.h"
#include "server/jobs/job_manager.h"
#include "server/reports/job_report_html.h"

namespace voxd::server {
namespace {

// The limits: the query's when it gives any, else those of the analysis the
// job asked for when it was submitted.
api::Fields limits_of(const httplib::Request& req, const JobSnapshot& job) {
  api::Fields fields;
  for (const char* name : {"min_wall", "max_wall"})
    if (req.has_param(name)) fields.emplace_back(name, req.get_param_value(name));
  for (const auto& [name, value] : req.params)
    if (name != "min_wall" && name != "max_wall") fields.emplace_back(name, value);  // refused by the parser
  if (!fields.empty() || !job.analyses.is_array()) return fields;
  for (const auto& entry : job.analyses) {
    const nlohmann::json& r = entry.value("request", nlohmann::json::object());
    if (r.value("kind", "") != "analysis") continue;
    for (const char* name : {"min_wall", "max_wall"})
      if (r.contains(name) && r[name].is_number()) fields.emplace_back(name, r[name].dump());
    break;
  }
  return fields;
}

}  // namespace

void install_report_route(RouteTable& routes, JobManager& jobs) {
  routes.get(kJobPath + "/report", [&jobs](const httplib::Request& req, httplib::Response& res) {
    const JobSnapshot job = succeeded_job(jobs, req.matches[1], "report", "its report exists");
    const api::AnalysisRequest analysis = analysis_request_of(api::AnalysisKind::analysis, limits_of(req, job));
    const nlohmann::json report = nlohmann::json::parse(*analyse_succeeded_job(jobs, job, analysis).bytes);
    std::vector<ReportPicture> pictures;
    for (const char* view : {"+z", "-y", "+x"}) {
      const api::AnalysisRequest preview =
          analysis_request_of(api::AnalysisKind::preview, {{"view", view}, {"colour", report.value("thickness", nlohmann::json()).is_object() ? "thickness" : "none"}});
      pictures.push_back({std::string("from ") + view + (preview.colour == "thickness" ? ", coloured by wall thickness" : ""),
                          std::move(*analyse_succeeded_job(jobs, job, preview).bytes)});
    }
    // The file's name without its extension, in characters safe in a header.
    std::string stem = job.labels.name.empty() ? job.id : job.labels.name.substr(0, job.labels.name.rfind('.'));
    for (char& c : stem)
      if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.' && c != '-' && c != '_') c = '_';
    if (stem.empty()) stem = job.id;
    res.set_header("Content-Disposition", "attachment; filename=\"" + stem + "-report.html\"");
    res.set_content(job_report_html(job_status_json(job), job.job->mode_name(), report, pictures), "text/html; charset=utf-8");
  });
}

}  // namespace voxd::server
