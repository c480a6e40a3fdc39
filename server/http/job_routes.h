#pragma once
// The job resource: POST and GET /v1/jobs (submit, list), GET and DELETE
// /v1/jobs/{id} (state, cancel or delete) and GET /v1/jobs/{id}/volume (the
// result in any format its mode can take).
#include "api/bounded_json.h"

namespace voxd::server {

class RouteTable;
class JobManager;
class Metrics;
struct ServeConfig;

void install_job_routes(RouteTable& routes, JobManager& jobs, Metrics& metrics, const ServeConfig& config,
                        const api::JsonLimits& params_limits);

}  // namespace voxd::server
