#include "server/http/routes.h"

#include <httplib.h>

#include "server/http/http_api.h"
#include "server/http/json_response.h"
#include "server/http/metrics.h"
#include "server/http/openapi_document.h"
#include "server/http/route_table.h"
#include "server/http/server_config.h"
#include "server/jobs/job_manager.h"

namespace voxd::server {

void install_service_routes(RouteTable& routes, JobManager& jobs, Metrics& metrics, const ServeConfig& config,
                            const std::atomic<bool>& draining) {
  using httplib::Request;
  using httplib::Response;
  routes.get("/healthz", [](const Request&, Response& res) { send_json(res, 200, {{"status", "ok"}}); });
  routes.get("/readyz", [&](const Request&, Response& res) {
    if (draining || !jobs.accepting()) return send_json(res, 503, {{"status", "not ready"}, {"reason", "shutting down"}});
    if (!jobs.backend_ok())
      return send_json(res, 503, {{"status", "not ready"}, {"reason", "the shared backend (Redis) is unreachable"}});
    if (jobs.counts().queue_depth >= config.queue_size)
      return send_json(res, 503, {{"status", "not ready"}, {"reason", "the job queue is full"}});
    if (const auto full = jobs.storage_full()) return send_json(res, 503, {{"status", "not ready"}, {"reason", *full}});
    send_json(res, 200, {{"status", "ready"}});
  });
  routes.get("/metrics", [&](const Request&, Response& res) {
    res.set_content(metrics.render(jobs.counts()), "text/plain; version=0.0.4; charset=utf-8");
  });
  routes.get("/openapi.json", [](const Request&, Response& res) { res.set_content(served_openapi_document(), "application/json"); });
}

}  // namespace voxd::server
