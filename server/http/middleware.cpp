#include "server/http/middleware.h"

#include <strings.h>

#include <chrono>
#include <cstdio>
#include <random>
#include <string>

#include <httplib.h>
#include <spdlog/spdlog.h>
#include <nlohmann/json.hpp>

#include "server/http/caller.h"
#include "server/http/connection_server.h"
#include "server/http/metrics.h"
#include "server/http/problem.h"
#include "server/http/route_label.h"
#include "server/http/server_config.h"
#include "server/http/submission.h"
#include "server/log_safe.h"
#include "server/tenants/request_rate.h"
#include "server/tenants/tenant_directory.h"

namespace voxd::server {
namespace {

using httplib::Request;
using httplib::Response;
using nlohmann::json;

struct RequestClock {
  std::chrono::steady_clock::time_point start;
  std::string request_id;
};
thread_local RequestClock current_request;
std::string new_request_id() {
  thread_local std::mt19937_64 rng{std::random_device{}()};
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(rng()));
  return buf;
}

// Every request gets an id (the client's, if it is a plain token) in its
// answer and its log line; its clock starts.
void start_request(const Request& req, Response& res) {
  // The head is parsed: the body's deadline applies from here, and a body the
  // answer leaves unread closes the connection (a 401 or a preflight answers
  // before httplib reads it).
  begin_request_body(req);
  current_request.start = std::chrono::steady_clock::now();
  const std::string client_id = req.get_header_value("X-Request-Id");
  current_request.request_id = is_plain_request_id(client_id) ? client_id : new_request_id();
  res.set_header("X-Request-Id", current_request.request_id);
}

// CORS for allowed web front ends; true when this was a preflight, answered.
bool answer_cors(const Request& req, Response& res, const ServeConfig& config) {
  const std::string origin = req.get_header_value("Origin");
  bool cors = false;
  if (!origin.empty())
    for (const auto& o : config.cors_origins) cors = cors || o == "*" || o == origin;
  if (!cors) return false;
  res.set_header("Access-Control-Allow-Origin", origin);
  res.set_header("Vary", "Origin");
  res.set_header("Access-Control-Expose-Headers", "Location, Retry-After, X-Request-Id, X-Voxd-Job-Id, X-Voxd-Dims, X-Voxd-Filled-Voxels, X-Voxd-Value-Type, X-Voxd-Scale, X-Voxd-Cache, Content-Disposition");
  if (req.method != "OPTIONS" || !req.has_header("Access-Control-Request-Method")) return false;
  res.set_header("Access-Control-Allow-Methods", "GET, POST, DELETE, OPTIONS");
  res.set_header("Access-Control-Allow-Headers", "Authorization, Content-Type, X-Request-Id");
  res.set_header("Access-Control-Max-Age", "600");
  res.status = 204;
  return true;
}

// Who asks (server/http/caller.h): the tenant its key names on the /v1
// routes, within its request rate; probes, metrics and the page stay open.
// True when the request was refused.
bool refuse_caller(const Request& req, Response& res, TenantDirectory& tenants, RequestRate& rate, Metrics& metrics) {
  Caller caller;
  caller.tenant.admin = tenants.unnamed_sees_all();
  if (req.path.rfind("/v1/", 0) != 0 || !tenants.needs_key()) {
    set_current_caller(std::move(caller));
    return false;
  }
  const std::string auth = req.get_header_value("Authorization");
  std::optional<Tenant> tenant;
  // The scheme is case-insensitive (RFC 9110 11.1): "bearer KEY" is as good.
  if (auth.size() > 7 && strncasecmp(auth.c_str(), "Bearer ", 7) == 0) tenant = tenants.authenticate(auth.substr(7));
  if (!tenant) {
    set_current_caller(Caller{Tenant{"", false, {}, {}}});
    metrics.count_rejected("unauthorized");
    res.set_header("WWW-Authenticate", "Bearer");
    send_problem(res, make_problem(401, "unauthorized", "Unauthorized", "this service needs an API key: send Authorization: Bearer KEY"), req.path);
    return true;
  }
  const bool sees_all = tenant->name.empty() && caller.tenant.admin;
  caller.tenant = std::move(*tenant);
  caller.tenant.admin = caller.tenant.admin || sees_all;
  metrics.count_tenant_request(caller.tenant.name);
  if (const std::optional<int> wait = rate.take(caller.tenant.name, caller.tenant.quotas.requests_per_minute)) {
    metrics.count_rejected("quota-exceeded");
    metrics.count_tenant_rejected(caller.tenant.name, "requests_per_minute");
    send_problem(res,
                 quota_exceeded("this tenant may make " + std::to_string(caller.tenant.quotas.requests_per_minute) +
                                    " requests a minute (to each replica); retry in " + std::to_string(*wait) + " s",
                                *wait),
                 req.path);
    set_current_caller(std::move(caller));
    return true;
  }
  set_current_caller(std::move(caller));
  return false;
}

}  // namespace

void install_middleware(httplib::Server& server, const ServeConfig& config, Metrics& metrics, TenantDirectory& tenants) {
  static RequestRate rate;  // one service a process
  server.set_pre_routing_handler([&config, &metrics, &tenants](const Request& req, Response& res) {
    start_request(req, res);
    if (answer_cors(req, res, config) || refuse_caller(req, res, tenants, rate, metrics))
      return httplib::Server::HandlerResponse::Handled;
    return httplib::Server::HandlerResponse::Unhandled;
  });

  // Clients that ask before sending a body (curl does for large uploads) learn
  // at once that it is too large.
  server.set_expect_100_continue_handler([&config, &metrics](const Request& req, Response& res) {
    if (declared_length(req).value_or(0) > config.max_upload_bytes) {
      metrics.count_rejected("upload-too-large");
      send_problem(res, upload_too_large(config.max_upload_bytes).problem(), req.path);
      res.set_header("Connection", "close");
      close_connection_after_response();
      return 413;
    }
    return 100;
  });

  // Errors httplib produces itself (unknown route, body over the limit,
  // unparsable request) get problem bodies too.
  server.set_error_handler([&config, &metrics](const Request& req, Response& res) {
    if (!res.body.empty()) return;
    if (res.status == 404)
      send_problem(res, make_problem(404, "not-found", "Not found", "no route " + req.method + " " + req.path), req.path);
    else if (res.status == 413) {
      close_connection_after_response();  // httplib left the body unread
      metrics.count_rejected("upload-too-large");
      send_problem(res, make_problem(413, "upload-too-large", "Upload too large",
                                     "the request body is over the limit of " + std::to_string(config.max_upload_bytes) + " bytes"),
                   req.path);
    } else
      send_problem(res, make_problem(res.status, "bad-request", "Bad request", "the request could not be read"), req.path);
  });

  server.set_logger([&config, &metrics](const Request& req, const Response& res) {
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - current_request.start).count();
    metrics.count_request(req.method, route_label(req.path), res.status);
    // A body sent from a provider of known length has it there.
    const std::size_t bytes = res.body.empty() ? res.content_length_ : res.body.size();
    metrics.add_bytes_out(bytes);
    if (config.log_format == "json")
      spdlog::info(json{{"event", "request"}, {"method", req.method}, {"path", req.path}, {"status", res.status},
                        {"bytes", bytes}, {"duration_ms", ms}, {"request_id", current_request.request_id}}
                       // Paths are not always UTF-8: replace, never throw.
                       .dump(-1, ' ', false, json::error_handler_t::replace));
    else
      spdlog::info("{} {} {} {}B {:.1f}ms id={}", log_safe(req.method), log_safe(req.path), res.status, bytes, ms,
                   current_request.request_id);
  });
}

}  // namespace voxd::server
