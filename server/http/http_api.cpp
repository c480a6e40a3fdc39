#include "server/http/http_api.h"

#include <httplib.h>

#include "server/http/middleware.h"
#include "server/http/route_label.h"
#include "server/http/route_table.h"
#include "server/http/routes.h"

namespace voxd::server {

void HttpApi::install(httplib::Server& server) {
  prepare_route_labels();  // and with it the served OpenAPI document
  install_middleware(server, config_, metrics_, tenants_);
  RouteTable routes(server, metrics_);
  install_service_routes(routes, jobs_, metrics_, config_, draining_);
  install_job_routes(routes, jobs_, metrics_, config_, params_limits_, tenants_);
  install_analysis_routes(routes, jobs_);
  install_report_route(routes, jobs_);
  install_mode_routes(routes, jobs_);
  install_event_routes(routes, jobs_, metrics_);
  install_web_routes(routes);
  install_voxelize_route(routes, jobs_, metrics_, config_, params_limits_);
  routes.refuse_other_methods();
}

}  // namespace voxd::server
