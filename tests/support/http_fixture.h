#pragma once
// The integration tests' fixture: a real `voxd serve` on a loopback
// ephemeral port in a fresh data directory, an HTTP client, helpers that
// check a JSON answer or an RFC 9457 problem, and a collector that validates
// every JSON body against the OpenAPI schemas when the test ends.
#include <algorithm>
#include <cstring>
#include <map>
#include <sstream>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "support/http_client.h"
#include "support/run_process.h"
#include "support/server_process.h"
#include "support/test_checks.h"
#include "support/test_meshes.h"

namespace voxd::test {

inline std::vector<std::uint8_t> bytes_of(const std::string& s) { return {s.begin(), s.end()}; }
inline std::string text_of(const std::vector<std::uint8_t>& b) { return {b.begin(), b.end()}; }

// A PNG answer as the independent reader decodes it (test::decode_png).
inline nlohmann::json read_png(const std::string& bytes) { return decode_png(bytes_of(bytes)); }

// An NRRD file: its header fields and the data after the blank line.
struct Nrrd {
  std::map<std::string, std::string> fields;
  std::string data;
};
inline Nrrd parse_nrrd(const std::string& bytes) {
  Nrrd n;
  const std::size_t end = bytes.find("\n\n");
  EXPECT_NE(end, std::string::npos);
  EXPECT_EQ(bytes.rfind("NRRD0004\n", 0), 0u);
  std::istringstream lines(bytes.substr(0, end));
  for (std::string line; std::getline(lines, line);) {
    const auto colon = line.find(": ");
    if (line.empty() || line[0] == '#' || colon == std::string::npos) continue;
    n.fields[line.substr(0, colon)] = line.substr(colon + 2);
  }
  if (end != std::string::npos) n.data = bytes.substr(end + 2);
  return n;
}

// Little-endian float32 data as floats.
inline std::vector<float> floats_of(const std::string& bytes) {
  std::vector<float> v(bytes.size() / 4);
  std::memcpy(v.data(), bytes.data(), v.size() * 4);
  return v;
}

class HttpServiceTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = make_temp_dir("voxd-http");
    schemas_ = std::make_unique<SchemaCollector>(dir_ + "/responses");
  }
  void TearDown() override {
    if (schemas_->count() > 0) {
      std::string output;
      EXPECT_EQ(schemas_->validate(&output), 0) << output;
    }
    if (server_ && server_->running()) {
      EXPECT_EQ(server_->stop(), 0) << server_->log();
    }
    server_.reset();
    std::filesystem::remove_all(dir_);
  }

  void start(std::vector<std::string> args = {}, std::vector<std::string> env = {},
             const std::vector<std::string>& launcher = {}) {
    if (std::find(args.begin(), args.end(), "--workers") == args.end()) {
      args.push_back("--workers");
      args.push_back("2");
    }
    server_ = std::make_unique<ServerProcess>(dir_ + "/data", args, env, launcher);
    client_ = make_client(server_->port());
  }
  httplib::Client& http() { return *client_; }

  // A JSON answer with its status, recorded for the schema check.
  nlohmann::json expect_json(const httplib::Result& res, int status, const std::string& component) {
    EXPECT_TRUE(res) << "no response";
    if (!res) return nlohmann::json();
    EXPECT_EQ(res->status, status) << res->body;
    EXPECT_EQ(res->get_header_value("Content-Type"), "application/json") << res->body;
    schemas_->add(component, res->body);
    return nlohmann::json::parse(res->body);
  }

  // An RFC 9457 problem with the expected status and type.
  nlohmann::json expect_problem(const httplib::Result& res, int status, const std::string& slug) {
    EXPECT_TRUE(res) << "no response";
    if (!res) return nlohmann::json();
    EXPECT_EQ(res->status, status) << res->body;
    EXPECT_EQ(res->get_header_value("Content-Type"), "application/problem+json") << res->body;
    schemas_->add("Problem", res->body);
    const nlohmann::json p = nlohmann::json::parse(res->body);
    EXPECT_EQ(p.at("type"), "urn:voxd:problem:" + slug) << res->body;
    EXPECT_EQ(p.at("status"), status);
    EXPECT_FALSE(p.at("title").get<std::string>().empty());
    EXPECT_GT(p.at("detail").get<std::string>().size(), 10u) << "a message a user can act on";
    return p;
  }

  nlohmann::json submit(const std::vector<std::uint8_t>& mesh, const std::string& params, const std::string& filename = "part.stl") {
    return expect_json(post_multipart(http(), "/v1/jobs", mesh, filename, params), 202, "JobStatus");
  }

  // Waits for a submitted job, expects it to succeed (its final status is
  // checked against the OpenAPI schema with the rest) and returns its id.
  std::string finished(const nlohmann::json& job) {
    const std::string id = job.at("id");
    const nlohmann::json done = wait_for_job(http(), id);
    EXPECT_EQ(done.at("state"), "succeeded") << done.dump();
    schemas_->add("JobStatus", done.dump());
    return id;
  }

  std::string volume(const std::string& id, const std::string& query = "") {
    auto res = http().Get(("/v1/jobs/" + id + "/volume" + query).c_str());
    EXPECT_TRUE(res);
    if (!res) return {};
    EXPECT_EQ(res->status, 200) << res->body;
    return res->body;
  }

  // The CLI's output for the same mesh bytes and parameters.
  std::string cli_volume(const std::vector<std::uint8_t>& mesh, const std::string& filename, const std::string& params,
                         const std::string& format = "rle") {
    const std::string in = dir_ + "/" + filename, out = dir_ + "/cli-out." + format;
    write_file(in, mesh);
    std::ofstream(dir_ + "/params.json") << params;
    const auto r = run_process(std::string(VOXD_BINARY) + " voxelize " + in + " -o " + out + " --format " + format +
                               " --params @" + dir_ + "/params.json");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return text_of(read_file(out));
  }

  std::string dir_;
  std::unique_ptr<ServerProcess> server_;
  std::unique_ptr<httplib::Client> client_;
  std::unique_ptr<SchemaCollector> schemas_;
};

}  // namespace voxd::test
