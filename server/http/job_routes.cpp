#include "server/http/routes.h"

#include <httplib.h>

#include "server/http/caller.h"
#include "server/http/job_labels.h"
#include "server/http/job_lookup.h"
#include "server/http/json_response.h"
#include "server/http/metrics.h"
#include "server/http/mode_routes.h"
#include "server/http/route_table.h"
#include "server/http/server_config.h"
#include "server/http/submission.h"
#include "server/http/surface_mesh_answer.h"
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

// A tenant's job quotas, checked before its upload is read (a refused body
// closes the connection: connection_server.h). Counted at this moment, so
// submissions racing each other may each pass: a quota is held to within
// the submissions in flight at once.
void check_job_quotas(const JobManager& jobs, const Caller& caller, Metrics& metrics) {
  const TenantQuotas& q = caller.tenant.quotas;
  if (q.concurrent_jobs == 0 && q.queued_jobs == 0 && q.stored_bytes == 0) return;
  const TenantUsage u = jobs.usage(caller.tenant.name);
  auto refuse = [&](const char* quota, const std::string& detail, int retry_after) {
    metrics.count_rejected("quota-exceeded");
    metrics.count_tenant_rejected(caller.tenant.name, quota);
    throw ProblemError(quota_exceeded(detail, retry_after));
  };
  if (q.queued_jobs > 0 && u.queued >= q.queued_jobs)
    refuse("queued_jobs", "your tenant has " + std::to_string(u.queued) + " jobs waiting for a worker, its quota of queued jobs; retry when one has started", 5);
  if (q.concurrent_jobs > 0 && u.queued + u.running >= q.concurrent_jobs)
    refuse("concurrent_jobs", "your tenant has " + std::to_string(u.queued + u.running) +
                                  " jobs queued or running, its quota of concurrent jobs; retry when one has finished", 5);
  if (q.stored_bytes > 0 && u.stored_bytes >= q.stored_bytes)
    refuse("stored_bytes", "your tenant's results take " + std::to_string(u.stored_bytes) + " bytes, at or over its quota of " +
                               std::to_string(q.stored_bytes) + "; delete jobs you no longer need (DELETE /v1/jobs/{id}) or wait for them to expire", 60);
}

}  // namespace

void install_job_routes(RouteTable& routes, JobManager& jobs, Metrics& metrics, const ServeConfig& config,
                        const api::JsonLimits& params_limits, TenantDirectory& tenants) {
  routes.post_upload("/v1/jobs", [&](const Request& req, Response& res, const httplib::ContentReader& reader) {
    const Caller& caller = current_caller();
    check_job_quotas(jobs, caller, metrics);
    Submission s = read_submission(req, reader, metrics, config.max_upload_bytes, params_limits);
    const JobLabels labels = job_labels_of(s, caller, tenants);
    const JobSnapshot job = jobs.submit(std::move(s.mesh), s.filename, s.params, labels);
    metrics.count_tenant_job(caller.tenant.name);
    res.set_header("Location", "/v1/jobs/" + job.id);
    send_json(res, 202, job_status_json(job));
  });
  routes.get("/v1/jobs", [&](const Request& req, Response& res) {
    const std::size_t offset = query_size(req, "offset", 0, 0, std::size_t{1} << 40);
    const std::size_t limit = query_size(req, "limit", 20, 1, 100);
    const JobFilter filter = job_filter_of(req, current_caller());
    std::size_t total = 0;
    json list = json::array();
    for (const auto& job : jobs.list(offset, limit, &total, filter)) list.push_back(job_status_json(job));
    const bool more = offset + limit < total;
    // The next page keeps the filter.
    std::string filters;
    if (!filter.name.empty()) filters += "&name=" + httplib::detail::encode_query_param(filter.name);
    for (const auto& [key, value] : filter.tags) filters += "&tag=" + httplib::detail::encode_query_param(key + ":" + value);
    send_json(res, 200, {{"jobs", list}, {"total", total}, {"offset", offset}, {"limit", limit},
                         {"next", more ? json("/v1/jobs?offset=" + std::to_string(offset + limit) + "&limit=" + std::to_string(limit) + filters)
                                       : json(nullptr)}});
  });

  routes.get(kJobPath, [&](const Request& req, Response& res) {
    send_json(res, 200, job_status_json(known_job(jobs, req.matches[1])));
  });
  routes.del(kJobPath, [&](const Request& req, Response& res) {
    const std::string id = req.matches[1];
    (void)known_job(jobs, id);  // another tenant's is unknown here
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
    if (is_mesh_format(v.format)) return answer_surface_mesh(res, jobs, job, v, filename, metrics);
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
