#include "server/http/mode_routes.h"

#include <algorithm>
#include <string>

#include <httplib.h>
#include <nlohmann/json.hpp>

#include "api/job_params.h"
#include "server/http/problem.h"
#include "voxd/byte_sink.h"
#include "voxd/encode/png_stack.h"

namespace voxd::server {
namespace {

using httplib::Request;
using httplib::Response;

ProblemError unknown_job(const std::string& id) {
  return ProblemError(make_problem(404, "not-found", "Unknown job", "no job with id " + id + " (it may have expired or been deleted)"));
}

JobSnapshot succeeded_job(JobManager& jobs, const std::string& id) {
  const auto job = jobs.get(id);
  if (!job) throw unknown_job(id);
  if (job->state != JobState::succeeded)
    throw ProblemError(make_problem(409, "job-not-finished", "The job has no result yet",
                                    std::string("the job is ") + to_string(job->state) + "; its result exists once it has succeeded"));
  return *job;
}

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

std::vector<std::string> install_mode_routes(httplib::Server& server, JobManager& jobs, const std::string& job_path,
                                             const Guard& guarded) {
  std::vector<std::string> patterns;
  std::vector<std::string> documents;
  for (const api::JobMode* mode : api::job_modes())
    for (const std::string& d : mode->documents())
      if (std::find(documents.begin(), documents.end(), d) == documents.end()) documents.push_back(d);
  for (const std::string& document : documents) {
    const std::string path = job_path + "/" + document;
    server.Get(path, guarded([&jobs, document](const Request& req, Response& res) {
      const JobSnapshot job = succeeded_job(jobs, req.matches[1]);
      const api::JobMode& mode = *job.job->mode;
      if (!has_document(mode, document))
        throw wrong_mode(job, "the " + document, [&](const api::JobMode& m) { return has_document(m, document); });
      nlohmann::json body = mode.document(document, *job.job, volumes_of(jobs, job));
      body["job"] = job.id;
      res.set_content(body.dump(2), "application/json");
    }));
    patterns.push_back(path);
  }

  const std::string layer_path = job_path + "/layers/(\\d{1,9})";
  server.Get(layer_path, guarded([&jobs](const Request& req, Response& res) {
    const JobSnapshot job = succeeded_job(jobs, req.matches[1]);
    if (!job.job->mode->colour_values())
      throw wrong_mode(job, "PNG layers", [](const api::JobMode& m) { return m.colour_values(); });
    const auto values = volumes_of(jobs, job)("values");
    const auto& colours = std::get<DenseVolume<Rgba8>>(*values);
    const std::int64_t k = std::stoll(req.matches[2]);
    if (k >= colours.grid().dims.z)
      throw ProblemError(make_problem(404, "not-found", "No such layer",
                                      "layer " + std::to_string(k) + " is outside 0.." + std::to_string(colours.grid().dims.z - 1) +
                                          " (the grid's z layers)"));
    VectorSink out;
    write_png_layer(colours, k, out);
    res.set_content(std::string(out.data.begin(), out.data.end()), "image/png");
  }));
  patterns.push_back(layer_path);
  return patterns;
}

}  // namespace voxd::server
