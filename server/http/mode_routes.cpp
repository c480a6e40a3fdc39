#include "server/http/mode_routes.h"

#include <algorithm>
#include <string>

#include <httplib.h>
#include <nlohmann/json.hpp>

#include "api/job_params.h"
#include "server/http/job_lookup.h"
#include "server/http/problem.h"
#include "server/http/route_table.h"
#include "server/http/routes.h"
#include "voxd/byte_sink.h"
#include "voxd/encode/png_stack.h"
#include "voxd/encode/number_text.h"

namespace voxd::server {
namespace {

using httplib::Request;
using httplib::Response;

ProblemError wrong_mode(const JobSnapshot& job, const std::string& what, const std::function<bool(const api::JobMode&)>& has) {
  return ProblemError(make_problem(409, "wrong-mode", "Not available for this job's mode",
                                   what + " exists for jobs with \"mode\": " + api::modes_with(has) + "; this job's mode is " +
                                       job.job->mode_name()));
}

bool has_document(const api::JobMode& mode, const std::string& name) {
  for (const std::string& d : mode.documents())
    if (d == name) return true;
  return false;
}

}  // namespace

api::VolumeSource volumes_of(JobManager& jobs, const JobSnapshot& job) {
  return [&jobs, id = job.id](const std::string& name) {
    auto volume = jobs.layer(id, name);
    if (!volume) throw unknown_job(id);
    return volume;
  };
}

std::shared_ptr<const ValueVolume> job_layer(JobManager& jobs, const JobSnapshot& job, const std::string& layer) {
  try {
    return job.job->mode->layer(layer, *job.job, volumes_of(jobs, job));
  } catch (const api::QueryRejected& e) {
    throw ProblemError(make_problem(400, "invalid-query", "Invalid query parameter", e.what()));
  }
}

void install_mode_routes(RouteTable& routes, JobManager& jobs) {
  std::vector<std::string> documents;
  for (const api::JobMode* mode : api::job_modes())
    for (const std::string& d : mode->documents())
      if (std::find(documents.begin(), documents.end(), d) == documents.end()) documents.push_back(d);
  for (const std::string& document : documents) {
    routes.get(kJobPath + "/" + document, [&jobs, document](const Request& req, Response& res) {
      const JobSnapshot job = succeeded_job(jobs, req.matches[1], "result", "its result exists");
      const api::JobMode& mode = *job.job->mode;
      if (!has_document(mode, document))
        throw wrong_mode(job, "the " + document, [&](const api::JobMode& m) { return has_document(m, document); });
      nlohmann::json body = mode.document(document, *job.job, volumes_of(jobs, job));
      body["job"] = job.id;
      res.set_content(body.dump(2), "application/json");
    });
  }

  routes.get(kJobPath + "/layers/(\\d{1,9})", [&jobs](const Request& req, Response& res) {
    const JobSnapshot job = succeeded_job(jobs, req.matches[1], "result", "its result exists");
    if (!job.job->mode->colour_values())
      throw wrong_mode(job, "PNG layers", [](const api::JobMode& m) { return m.colour_values(); });
    const auto values = volumes_of(jobs, job)("values");
    const auto& colours = std::get<DenseVolume<Rgba8>>(*values);
    const std::int64_t k = parse_number<std::int64_t>(req.matches[2].str()).value();  // the route matched 1-9 digits
    if (k >= colours.grid().dims.z)
      throw ProblemError(make_problem(404, "not-found", "No such layer",
                                      "layer " + std::to_string(k) + " is outside 0.." + std::to_string(colours.grid().dims.z - 1) +
                                          " (the grid's z layers)"));
    VectorSink out;
    write_png_layer(colours, k, out);
    res.set_content(std::string(out.data.begin(), out.data.end()), "image/png");
  });
}

}  // namespace voxd::server
