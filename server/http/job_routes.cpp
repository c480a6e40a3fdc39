#include "server/http/routes.h"

#include <httplib.h>

#include "server/http/job_lookup.h"
#include "server/http/json_response.h"
#include "server/http/metrics.h"
#include "server/http/mode_routes.h"
#include "server/http/route_table.h"
#include "server/http/server_config.h"
#include "server/http/submission.h"
#include "server/http/volume_request.h"
#include "server/http/job_status.h"
#include "server/jobs/job_record.h"
#include "voxd/encode/number_text.h"
#include "voxd/encode/slab_writer.h"
#include "voxd/error.h"

namespace voxd::server {
namespace {

using httplib::Request;
using httplib::Response;
using nlohmann::json;

std::size_t query_size(const Request& req, const char* name, std::size_t fallback, std::size_t lo, std::size_t hi) {
  if (!req.has_param(name)) return fallback;
  const std::string v = req.get_param_value(name);
  if (const auto n = parse_number<std::size_t>(v); n && *n >= lo && *n <= hi) return *n;
  throw ProblemError(make_problem(400, "invalid-query", "Invalid query parameter",
                                  std::string(name) + " must be an integer between " + std::to_string(lo) + " and " +
                                      std::to_string(hi) + ", got '" + v + "'"));
}

}  // namespace

void install_job_routes(RouteTable& routes, JobManager& jobs, Metrics& metrics, const ServeConfig& config,
                        const api::JsonLimits& params_limits) {
  routes.post_upload("/v1/jobs", [&](const Request& req, Response& res, const httplib::ContentReader& reader) {
    Submission s = read_submission(req, reader, metrics, config.max_upload_bytes, params_limits);
    const JobSnapshot job = jobs.submit(std::move(s.mesh), s.filename, s.params);
    res.set_header("Location", "/v1/jobs/" + job.id);
    send_json(res, 202, job_status_json(job));
  });
  routes.get("/v1/jobs", [&](const Request& req, Response& res) {
    const std::size_t offset = query_size(req, "offset", 0, 0, std::size_t{1} << 40);
    const std::size_t limit = query_size(req, "limit", 20, 1, 100);
    std::size_t total = 0;
    json list = json::array();
    for (const auto& job : jobs.list(offset, limit, &total)) list.push_back(job_status_json(job));
    const bool more = offset + limit < total;
    send_json(res, 200, {{"jobs", list}, {"total", total}, {"offset", offset}, {"limit", limit},
                         {"next", more ? json("/v1/jobs?offset=" + std::to_string(offset + limit) + "&limit=" + std::to_string(limit)) : json(nullptr)}});
  });

  routes.get(kJobPath, [&](const Request& req, Response& res) {
    const auto job = jobs.get(req.matches[1]);
    if (!job) throw unknown_job(req.matches[1]);
    send_json(res, 200, job_status_json(*job));
  });
  routes.del(kJobPath, [&](const Request& req, Response& res) {
    const std::string id = req.matches[1];
    switch (jobs.cancel_or_delete(id)) {
      case JobManager::RemoveResult::not_found: throw unknown_job(id);
      case JobManager::RemoveResult::deleted: res.status = 204; return;
      case JobManager::RemoveResult::cancelled: {
        const auto job = jobs.get(id);
        send_json(res, 202, job ? job_status_json(*job) : json{{"id", id}, {"state", "cancelled"}});
        return;
      }
    }
  });

  routes.get(kJobPath + "/volume", [&](const Request& req, Response& res) {
    const std::string id = req.matches[1];
    VolumeRequest v = read_volume_request(req);
    const JobSnapshot job = succeeded_job(jobs, id, "volume", "its volume exists");
    v.options.content = volume_content(job, req.has_param("layer") ? req.get_param_value("layer") : "");
    const std::string filename = id + file_extension(v.format);
    if (job.job->mode->writes(v.format)) return answer_mode_written(res, job.job, volumes_of(jobs, job), v, filename, metrics);
    if (req.has_param("layer")) return answer_values(res, job_layer(jobs, job, req.get_param_value("layer")), v, filename, metrics);
    if (job.has_value_volume() && job.streamed) {
      // Made slab by slab: served slab by slab from the stored values in
      // the formats that stream, else loaded whole while they fit.
      check_format_holds(*job.job, v);
      const ValueVolume type = *job.job->value_type();
      if (!streaming_refusal(type, v.format, v.options)) {
        auto rle = jobs.values_rle(id);
        if (!rle) throw unknown_job(id);
        return answer_stored_values(res, std::move(rle), job.grid, type, v, filename, metrics);
      }
      const std::uint64_t bytes = job.grid.voxel_count() * (std::holds_alternative<DenseVolume<float>>(type) ? 4 : 1);
      if (bytes > jobs.max_job_memory())
        throw Error(ErrorCode::limit_exceeded,
                    *streaming_refusal(type, v.format, v.options) + "; this job's values were made slab by slab and, at " +
                        std::to_string(bytes >> 20) + " MiB, are over the per-job memory of " +
                        std::to_string(jobs.max_job_memory() >> 20) + " MiB: ask for format rle, raw or nrrd, which stream");
    }
    if (job.has_value_volume()) {
      auto values = jobs.values(id);
      if (!values) throw unknown_job(id);
      return answer_values(res, std::move(values), v, filename, metrics);
    }
    check_bits_format(v);
    // Made slab by slab or from its runs, the volume is kept as its RLE:
    // served slab by slab from it in the formats that stream.
    if (job.execution != ExecutionPath::memory && !streaming_refusal(v.format)) {
      auto rle = jobs.volume_rle(id);
      if (!rle) throw unknown_job(id);
      return answer_stored_bits(res, std::move(rle), v, filename, metrics);
    }
    if (job.streamed && bit_volume_bytes(job.grid.dims) > jobs.max_job_memory())
      throw Error(ErrorCode::limit_exceeded,
                  *streaming_refusal(v.format) + "; this job's volume was made slab by slab and, at " +
                      std::to_string(bit_volume_bytes(job.grid.dims) >> 20) + " MiB, is over the per-job memory of " +
                      std::to_string(jobs.max_job_memory() >> 20) + " MiB: ask for format rle, raw or nrrd, which stream");
    auto volume = jobs.volume(id);
    if (!volume) throw unknown_job(id);
    answer_bits(res, std::move(volume), v, filename, metrics);
  });
}

}  // namespace voxd::server
