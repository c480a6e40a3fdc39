#pragma once
// RFC 9457 problem details: every error the API returns, and the mapping from
// the engine's and the job manager's exceptions to statuses and slugs.
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

namespace httplib {
struct Response;
}

namespace voxd::server {

struct Problem {
  int status = 500;
  std::string slug;  // type is urn:voxd:problem:<slug>
  std::string title;
  std::string detail;
  nlohmann::json errors;  // [{path, message}] for parameter errors, else null
  std::vector<std::pair<std::string, std::string>> headers;  // e.g. Retry-After
};

// Thrown by request handling code to answer with a problem.
class ProblemError : public std::runtime_error {
 public:
  explicit ProblemError(Problem p) : std::runtime_error(p.detail), problem_(std::move(p)) {}
  const Problem& problem() const { return problem_; }

 private:
  Problem problem_;
};

Problem make_problem(int status, std::string slug, std::string title, std::string detail);
// 429 quota-exceeded: a tenant's quota (server/tenants/), with Retry-After.
Problem quota_exceeded(std::string detail, int retry_after_seconds);
// Maps the exception being handled (call inside a catch block).
Problem problem_from_current_exception();
void send_problem(httplib::Response& res, const Problem& p, const std::string& instance);

}  // namespace voxd::server
