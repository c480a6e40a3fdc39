#pragma once
// What every request goes through, whatever its route: a request id, CORS for
// allowed web front ends, the caller's tenant from its key (with its
// request rate), the early refusal of an
// upload that announces too large a body, problem+json bodies for the errors
// httplib answers itself, and the access log and request metrics.
namespace httplib {
class Server;
}

namespace voxd::server {

struct ServeConfig;
class Metrics;
class TenantDirectory;

void install_middleware(httplib::Server& server, const ServeConfig& config, Metrics& metrics, TenantDirectory& tenants);

}  // namespace voxd::server
