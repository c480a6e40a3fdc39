#include "server/http/routes.h"

#include <httplib.h>

#include "api/job_params.h"
#include "server/http/connection_server.h"
#include "server/http/problem.h"
#include "server/http/route_table.h"
#include "server/http/server_config.h"
#include "server/http/submission.h"
#include "server/http/volume_request.h"
#include "server/jobs/job_manager.h"

namespace voxd::server {
namespace {

// The volumes of a synchronous job's output, which is never stored.
api::VolumeSource sync_volumes(const JobOutput& output) {
  return [output](const std::string& name) -> std::shared_ptr<const ValueVolume> {
    if (name == "values") return output.values;
    for (const auto& [layer, volume] : output.layers)
      if (layer == name) return volume;
    throw std::logic_error("a synchronous job has no layer " + name);
  };
}

}  // namespace

void install_voxelize_route(RouteTable& routes, JobManager& jobs, Metrics& metrics, const ServeConfig& config,
                            const api::JsonLimits& params_limits) {
  routes.post_upload("/v1/voxelize", [&](const httplib::Request& req, httplib::Response& res,
                                         const httplib::ContentReader& reader) {
    VolumeRequest v = read_volume_request(req);
    Submission s = read_submission(req, reader, metrics, config.max_upload_bytes, params_limits);
    const api::JobParams params = api::parse_job_params(s.params);
    check_format_holds(params, v);  // before any work
    JobSnapshot job;
    // A client that gives up on the answer cancels the job.
    JobOutput output =
        jobs.run_sync(std::move(s.mesh), s.filename, s.params, &job, config.sync_max_voxels, request_client_gone);
    if (!output.solid) {
      Problem p = job.failure ? make_problem(job.failure->type == "internal" ? 500 : 422, job.failure->type, job.failure->title, job.failure->detail)
                              : make_problem(409, "cancelled", "The job was cancelled", "the job was cancelled");
      throw ProblemError(p);
    }
    res.set_header("X-Voxd-Job-Id", job.id);
    res.set_header("X-Voxd-Dims", std::to_string(job.grid.dims.x) + "," + std::to_string(job.grid.dims.y) + "," + std::to_string(job.grid.dims.z));
    res.set_header("X-Voxd-Filled-Voxels", std::to_string(job.filled_voxels.value_or(0)));
    v.options.content = volume_content(job);
    const std::string filename = "voxels" + std::string(file_extension(v.format));
    if (output.values && params.mode->writes(v.format))
      return answer_mode_written(res, job.job, sync_volumes(output), v, filename, metrics);
    if (output.values) return answer_values(res, std::move(output.values), v, filename, metrics);
    answer_bits(res, std::move(output.solid), v, filename, metrics);
  });
}

}  // namespace voxd::server
