#include "support/http_client.h"

#include <chrono>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <thread>

#include "support/run_process.h"

namespace voxd::test {

std::unique_ptr<httplib::Client> make_client(int port, int timeout_seconds) {
  auto client = std::make_unique<httplib::Client>("127.0.0.1", port);
  client->set_connection_timeout(10, 0);
  client->set_read_timeout(timeout_seconds, 0);
  client->set_write_timeout(timeout_seconds, 0);
  return client;
}

httplib::Result post_multipart(httplib::Client& client, const std::string& path, const std::vector<std::uint8_t>& mesh,
                               const std::string& filename, const std::string& params_text,
                               const httplib::Headers& headers) {
  httplib::MultipartFormDataItems items = {
      {"mesh", std::string(mesh.begin(), mesh.end()), filename, "application/octet-stream"},
      {"params", params_text, "", "application/json"},
  };
  return client.Post(path.c_str(), headers, items);
}

std::string url_encode(const std::string& text) {
  static const char* hex = "0123456789ABCDEF";
  std::string out;
  for (unsigned char c : text) {
    if (std::isalnum(c) || c == '-' || c == '_' || c == '.' || c == '~') {
      out += static_cast<char>(c);
    } else {
      out += '%';
      out += hex[c >> 4];
      out += hex[c & 15];
    }
  }
  return out;
}

httplib::Result post_raw(httplib::Client& client, const std::string& path, const std::vector<std::uint8_t>& mesh,
                         const std::string& params_text, const std::string& content_type) {
  const std::string target = params_text.empty() ? path : path + (path.find('?') == std::string::npos ? "?" : "&") + "params=" + url_encode(params_text);
  return client.Post(target.c_str(), reinterpret_cast<const char*>(mesh.data()), mesh.size(), content_type.c_str());
}

namespace {

// Polls GET /v1/jobs/ID until `done(job)`; throws after `seconds`.
template <class Done>
nlohmann::json poll_job(httplib::Client& client, const std::string& id, int seconds, Done done, const std::string& what) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(seconds);
  std::string last;
  while (std::chrono::steady_clock::now() < until) {
    auto res = client.Get(("/v1/jobs/" + id).c_str());
    if (!res) throw std::runtime_error("GET /v1/jobs/" + id + " failed: " + httplib::to_string(res.error()));
    if (res->status != 200) throw std::runtime_error("GET /v1/jobs/" + id + " answered " + std::to_string(res->status) + ": " + res->body);
    auto job = nlohmann::json::parse(res->body);
    last = job.at("state");
    if (done(job)) return job;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  throw std::runtime_error("job " + id + " did not " + what + " within " + std::to_string(seconds) + " s (last state: " + last + ")");
}

}  // namespace

nlohmann::json wait_for_state(httplib::Client& client, const std::string& id, const std::string& state, int seconds) {
  return poll_job(client, id, seconds, [&](const nlohmann::json& job) { return job.at("state") == state; }, "become " + state);
}

// Under AddressSanitizer the service runs several times slower (a 520^3
// winding job took over 180 s on 2 cores): waits for a job's end stretch by
// as much, so a sanitized run checks the same behaviour, not the clock.
#if defined(__SANITIZE_ADDRESS__)
constexpr int kSanitizerSlowdown = 5;
#else
constexpr int kSanitizerSlowdown = 1;
#endif

nlohmann::json wait_for_job(httplib::Client& client, const std::string& id, int seconds) {
  return poll_job(
      client, id, seconds * kSanitizerSlowdown,
      [](const nlohmann::json& job) {
        const std::string state = job.at("state");
        return state == "succeeded" || state == "failed" || state == "cancelled";
      },
      "end");
}

void SchemaCollector::add(const std::string& component, const std::string& body) {
  std::filesystem::create_directories(dir_);
  std::ofstream(dir_ + "/" + component + "." + std::to_string(count_++) + ".json") << body;
}

int SchemaCollector::validate(std::string* output) const {
  if (count_ == 0) return 0;
  const std::string source = VOXD_SOURCE_DIR;
  const auto r = run_process("/usr/bin/python3 " + source + "/tests/tools/check_openapi.py " + source +
                             "/proto-schemas/openapi.json " + source + "/proto-schemas/job-params.schema.json --responses " + dir_);
  if (output) *output = r.out + r.err;
  return r.exit_code;
}

}  // namespace voxd::test
