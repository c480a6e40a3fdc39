#pragma once
// Reading a job submission: either multipart/form-data (parts "mesh" and
// "params", and the optional "name", "tags", "callback") or the raw mesh as the body with params in the query string. The
// body is read here, through httplib's content reader, not by httplib before
// routing: that keeps `curl --data-binary` (sent as
// application/x-www-form-urlencoded) from being parsed as a form, and counts
// the bytes as they arrive, refusing an upload over the limit as it crosses it.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <httplib.h>
#include <nlohmann/json.hpp>

#include "api/bounded_json.h"
#include "server/http/problem.h"

namespace voxd::server {

class Metrics;

struct Submission {
  std::vector<std::uint8_t> mesh;
  std::string filename;
  nlohmann::json params;
  // The job's labels as sent (parts or query parameters "name", "tags" as
  // a JSON object, "callback"), checked by job_labels_of (job_labels.h).
  std::optional<std::string> name, tags, callback;
};

Submission read_submission(const httplib::Request& req, const httplib::ContentReader& reader, Metrics& metrics,
                           std::uint64_t max_bytes, const api::JsonLimits& params_limits);

// The declared body size, or UINT64_MAX for a value that is not a number
// (httplib itself refuses those before the body is read).
std::optional<std::uint64_t> declared_length(const httplib::Request& req);

ProblemError upload_too_large(std::uint64_t limit);

}  // namespace voxd::server
