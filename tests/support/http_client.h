#pragma once
// Small HTTP helpers over httplib::Client for the integration tests: job
// submission in both upload shapes, polling, and a collector of response
// bodies that are checked against the OpenAPI schemas by an independent
// validator (python3-jsonschema).
#include <memory>
#include <string>
#include <vector>

#include <httplib.h>
#include <nlohmann/json.hpp>

namespace voxd::test {

std::unique_ptr<httplib::Client> make_client(int port, int timeout_seconds = 120);

// POST /v1/jobs as multipart/form-data with parts mesh and params.
httplib::Result post_multipart(httplib::Client& client, const std::string& path, const std::vector<std::uint8_t>& mesh,
                               const std::string& filename, const std::string& params_text,
                               const httplib::Headers& headers = {});
// POST with the raw mesh as the body (as `curl --data-binary` sends it) and
// params in the query string.
httplib::Result post_raw(httplib::Client& client, const std::string& path, const std::vector<std::uint8_t>& mesh,
                         const std::string& params_text, const std::string& content_type = "application/x-www-form-urlencoded");

std::string url_encode(const std::string& text);

// Polls GET /v1/jobs/ID until the job has ended; throws after `seconds`.
nlohmann::json wait_for_job(httplib::Client& client, const std::string& id, int seconds = 120);
// Polls until the job is in `state`; throws after `seconds`.
nlohmann::json wait_for_state(httplib::Client& client, const std::string& id, const std::string& state, int seconds = 60);

// Saves bodies as DIR/<Component>.<n>.json and validates them all at once.
class SchemaCollector {
 public:
  explicit SchemaCollector(std::string dir) : dir_(std::move(dir)) {}
  void add(const std::string& component, const std::string& body);
  // Runs tests/tools/check_openapi.py over what was collected; returns its
  // exit code and fills `output`.
  int validate(std::string* output) const;
  int count() const { return count_; }

 private:
  std::string dir_;
  int count_ = 0;
};

}  // namespace voxd::test
