#pragma once
// The API's routes, grouped by resource, one .cpp each; http_api.cpp puts them
// together behind the middleware. Each registers through a RouteTable, so its
// handlers are guarded and other methods get 405.
//  - service_routes.cpp: /healthz, /readyz (not while draining, with a full
//    queue or a full disk), /metrics, /openapi.json; open without an API key.
//  - job_routes.cpp: POST and GET /v1/jobs (the caller's tenant's, with its
//    quotas, names and tags), GET and DELETE /v1/jobs/{id},
//    GET /v1/jobs/{id}/volume in any format the job's mode can take. Every
//    /v1/jobs/{id} route finds its job through job_lookup.h.
//  - analysis_routes.cpp: /v1/jobs/{id}/{analysis,radiography,section,
//    preview,thickness}, computed on first request from the stored volume
//    unless the worker prepared them (the job JSON's "analyses"), and kept
//    beside it (server/jobs/job_analyses.h).
//  - report_route.cpp: /v1/jobs/{id}/report, the job's report as one HTML
//    file to send (server/reports/job_report_html.h).
//  - mode_routes.cpp: what a mode serves beyond its volume (mode_routes.h).
//  - event_routes.cpp: GET /v1/jobs/{id}/events, the job's progress as
//    server-sent events (job_event_stream.h), on the stream threads.
//  - web_routes.cpp: the web page at / and its files under /ui/, from the
//    binary (web_assets.h); open without an API key, like the probes.
//  - voxelize_route.cpp: POST /v1/voxelize, a small job run at once, its
//    volume the answer, nothing stored.
#include <atomic>
#include <string_view>

#include "api/bounded_json.h"

namespace voxd::server {

class RouteTable;
class JobManager;
class Metrics;
class TenantDirectory;
struct ServeConfig;

void install_service_routes(RouteTable& routes, JobManager& jobs, Metrics& metrics, const ServeConfig& config,
                            const std::atomic<bool>& draining);
void install_job_routes(RouteTable& routes, JobManager& jobs, Metrics& metrics, const ServeConfig& config,
                        const api::JsonLimits& params_limits, TenantDirectory& tenants);
void install_analysis_routes(RouteTable& routes, JobManager& jobs);
void install_report_route(RouteTable& routes, JobManager& jobs);
void install_mode_routes(RouteTable& routes, JobManager& jobs);
void install_event_routes(RouteTable& routes, JobManager& jobs, Metrics& metrics);
void install_web_routes(RouteTable& routes);
void install_voxelize_route(RouteTable& routes, JobManager& jobs, Metrics& metrics, const ServeConfig& config,
                            const api::JsonLimits& params_limits);

}  // namespace voxd::server
