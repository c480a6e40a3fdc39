#include "server/http/problem.h"

#include <httplib.h>
#include <spdlog/spdlog.h>

#include "api/error_table.h"
#include "api/param_error.h"
#include "server/jobs/job.h"
#include "server/jobs/memory_budget.h"
#include "server/jobs/job_store.h"
#include "server/log_safe.h"
#include "voxd/error.h"

namespace voxd::server {

Problem make_problem(int status, std::string slug, std::string title, std::string detail) {
  Problem p;
  p.status = status;
  p.slug = std::move(slug);
  p.title = std::move(title);
  p.detail = std::move(detail);
  return p;
}

Problem quota_exceeded(std::string detail, int retry_after_seconds) {
  Problem p = make_problem(429, "quota-exceeded", "Quota exceeded", std::move(detail));
  p.headers.emplace_back("Retry-After", std::to_string(retry_after_seconds));
  return p;
}

Problem problem_from_current_exception() {
  try {
    throw;
  } catch (const ProblemError& e) {
    return e.problem();
  } catch (const api::InvalidParams& e) {
    Problem p = make_problem(422, "invalid-params", "Invalid job parameters", e.what());
    p.errors = nlohmann::json::array();
    for (const auto& f : e.errors()) p.errors.push_back({{"path", f.path}, {"message", f.message}});
    return p;
  } catch (const QueueFull& e) {
    Problem p = make_problem(429, "queue-full", "Too many jobs", e.what());
    p.headers.emplace_back("Retry-After", std::to_string(e.retry_after_seconds()));
    return p;
  } catch (const StorageFull& e) {
    Problem p = make_problem(507, "storage-full", "The service's storage is full", e.what());
    p.headers.emplace_back("Retry-After", "60");
    return p;
  } catch (const MemoryBusy& e) {
    Problem p = make_problem(429, "memory-busy", "The service's memory is taken", e.what());
    p.headers.emplace_back("Retry-After", std::to_string(MemoryBusy::kRetryAfterSeconds));
    return p;
  } catch (const BackendUnavailable& e) {
    spdlog::warn("request refused: {}", log_safe(e.what()));
    Problem p = make_problem(503, "backend-unavailable", "The service's shared backend is unavailable",
                             "the service cannot reach its job store (Redis) right now; retry in a few seconds");
    p.headers.emplace_back("Retry-After", "5");
    return p;
  } catch (const NotAccepting& e) {
    return make_problem(503, "shutting-down", "The service is shutting down", e.what());
  } catch (const Error& e) {
    const api::ErrorKind& kind = api::error_kind(e.code());
    if (kind.client_message) return make_problem(kind.http_status, kind.slug, kind.title, e.what());
    spdlog::error("request failed: {}", log_safe(e.what()));
    return make_problem(kind.http_status, kind.slug, kind.title, "the request failed unexpectedly; it was logged");
  } catch (const std::exception& e) {
    spdlog::error("request failed: {}", log_safe(e.what()));
    return make_problem(500, "internal", "Internal error", "the request failed unexpectedly; it was logged");
  }
}

void send_problem(httplib::Response& res, const Problem& p, const std::string& instance) {
  nlohmann::json body = {{"type", "urn:voxd:problem:" + p.slug},
                         {"title", p.title},
                         {"status", p.status},
                         {"detail", p.detail},
                         {"instance", instance}};
  if (!p.errors.is_null()) body["errors"] = p.errors;
  res.status = p.status;
  for (const auto& [name, value] : p.headers) res.set_header(name, value);
  res.set_content(body.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace), "application/problem+json");
}

}  // namespace voxd::server
