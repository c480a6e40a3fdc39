#include "server/http/job_status.h"

#include "server/http/surface_mesh_answer.h"
#include "server/jobs/job_record.h"
#include "voxd/encode/volume_format.h"

namespace voxd::server {

using nlohmann::json;

namespace {

std::string job_url(const std::string& id) { return "/v1/jobs/" + id; }

// The formats a succeeded job's volume is offered in (those
// GET /v1/jobs/{id}/volume does not refuse for its mode and value type, the
// meshes of its surface included), by name, each with its URL.
json downloads(const JobSnapshot& job) {
  json out = json::object();
  if (job.state != JobState::succeeded || !job.job) return out;
  for (const auto& [format, name] : kVolumeFormatNames)
    if (!job.job->format_refusal(format) || (is_mesh_format(format) && offers_surface_mesh(*job.job)))
      out[name] = job_url(job.id) + "/volume?format=" + name;
  return out;
}

}  // namespace

std::string analysis_url(const api::AnalysisRequest& r, const std::string& id) {
  return job_url(id) + "/" + to_string(r.kind) + "?" + r.query();
}

json analysis_status_entry(json entry, const std::string& id) {
  if (!entry.is_object() || !entry.contains("request")) return entry;
  const std::vector<api::AnalysisRequest> request = api::parse_analyses(json::array({entry.at("request")}));
  entry["url"] = analysis_url(request.at(0), id);
  return entry;
}

int failure_status(const std::string& type) {
  if (type == "interrupted") return 503;
  if (type == "internal") return 500;
  if (type == "storage-full") return 507;
  return 422;
}

json job_status_json(const JobSnapshot& job) {
  json out = record_json(job);
  const std::string self = job_url(job.id);
  out["links"] = {{"self", self}, {"volume", self + "/volume"}, {"events", self + "/events"}, {"downloads", downloads(job)}};
  if (job.failure) out["error"]["status"] = failure_status(job.failure->type);
  // Each requested analysis with the URL that serves it (the record keeps
  // the request; records of earlier releases kept the URL too).
  if (out["analyses"].is_array())
    for (json& entry : out["analyses"]) entry = analysis_status_entry(entry, job.id);
  return out;
}

}  // namespace voxd::server
