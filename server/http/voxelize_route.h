#pragma once
// POST /v1/voxelize: a small job run at once, its volume the answer, nothing
// stored.
#include "api/bounded_json.h"

namespace voxd::server {

class RouteTable;
class JobManager;
class Metrics;
struct ServeConfig;

void install_voxelize_route(RouteTable& routes, JobManager& jobs, Metrics& metrics, const ServeConfig& config,
                            const api::JsonLimits& params_limits);

}  // namespace voxd::server
