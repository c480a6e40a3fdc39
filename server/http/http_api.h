#pragma once
// The REST API: routes of proto-schemas/openapi.json over the job engine.
#include <atomic>
#include <string>

#include "api/bounded_json.h"
#include "server/http/metrics.h"
#include "server/http/server_config.h"
#include "server/jobs/job_manager.h"
#include "server/tenants/tenant_directory.h"

namespace httplib {
class Server;
}

namespace voxd::server {

class HttpApi {
 public:
  HttpApi(const ServeConfig& config, JobManager& jobs, Metrics& metrics, TenantDirectory& tenants)
      : config_(config), jobs_(jobs), metrics_(metrics), tenants_(tenants) {}
  void install(httplib::Server& server);
  // Readiness turns false for the rest of the process (SIGTERM received).
  void set_draining() { draining_ = true; }

 private:
  const ServeConfig& config_;
  JobManager& jobs_;
  Metrics& metrics_;
  TenantDirectory& tenants_;
  api::JsonLimits params_limits_;
  std::atomic<bool> draining_{false};
};

}  // namespace voxd::server
