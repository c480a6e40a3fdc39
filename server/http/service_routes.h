#pragma once
// The service's own routes, open without an API key: /healthz (liveness),
// /readyz (readiness: not while draining, with a full queue or a full disk),
// /metrics (Prometheus text) and /openapi.json (the contract).
#include <atomic>

namespace voxd::server {

class RouteTable;
class JobManager;
class Metrics;
struct ServeConfig;

void install_service_routes(RouteTable& routes, JobManager& jobs, Metrics& metrics, const ServeConfig& config,
                            const std::atomic<bool>& draining);

}  // namespace voxd::server
