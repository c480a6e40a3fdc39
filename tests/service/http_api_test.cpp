// Integration tests: the real `voxd serve` on a loopback ephemeral port,
// spoken to over HTTP. Results are compared byte for byte with the CLI on the
// same files, and every JSON body is validated against the published OpenAPI
// schemas by an independent validator.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>
#include <zlib.h>

#include <atomic>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <thread>

#include <gtest/gtest.h>

#include "support/draco_cli.h"
#include "support/http_client.h"
#include "support/http_fixture.h"
#include "support/run_process.h"
#include "support/server_process.h"
#include "support/test_meshes.h"
#include "support/test_parts.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd::test {
namespace {

using nlohmann::json;
using namespace std::chrono_literals;


std::vector<std::uint8_t> sphere_stl(double r = 1.0, int level = 3) {
  return to_binary_stl(make_icosphere({0, 0, 0}, r, level));
}
// An organic closed part (test_parts.h) as a user uploads it.
std::vector<std::uint8_t> blob_stl() { return to_binary_stl(test::part_mesh("blob.stl")); }

// A job that runs for minutes unless cancelled: generalized winding numbers
// at 1024 voxels along the blob.
const char* const kSlowParams = R"({"grid":{"resolution":1024},"inside":"winding"})";

class HttpApiTest : public HttpServiceTest {};

TEST_F(HttpApiTest, MultipartJobRunsAndItsVolumeEqualsTheCliInEveryFormat) {
  start();
  const auto mesh = sphere_stl();
  const std::string params = R"({"grid":{"resolution":40,"padding":1}})";
  auto res = post_multipart(http(), "/v1/jobs", mesh, "ball.stl", params);
  const json accepted = expect_json(res, 202, "JobStatus");
  const std::string id = accepted.at("id");
  EXPECT_EQ(res->get_header_value("Location"), "/v1/jobs/" + id);
  EXPECT_EQ(accepted.at("mesh_format"), "stl_binary");
  EXPECT_EQ(accepted.at("triangles"), 1280);
  EXPECT_EQ(accepted.at("grid").at("dims"), json::array({42, 42, 42}));

  const json done = wait_for_job(http(), id);
  schemas_->add("JobStatus", done.dump());
  ASSERT_EQ(done.at("state"), "succeeded") << done.dump();
  EXPECT_EQ(done.at("progress"), 1.0);
  EXPECT_TRUE(done.at("mesh").at("watertight"));
  EXPECT_EQ(done.at("links").at("volume"), "/v1/jobs/" + id + "/volume");
  for (const char* stage : {"parse", "grid", "voxelize"}) EXPECT_TRUE(done.at("timings").contains(stage)) << stage;
  // The filled count is the engine's, independently of the HTTP path.
  GridRequest g;
  g.resolution = 40;
  g.padding = 1;
  const Mesh m = make_icosphere({0, 0, 0}, 1.0, 3);
  EXPECT_EQ(done.at("filled_voxels").get<std::uint64_t>(), voxelize(m, resolve_grid(g, bounds(m)), {}).count());

  EXPECT_EQ(volume(id), cli_volume(mesh, "ball.stl", params, "rle"));
  EXPECT_EQ(volume(id, "?format=rle"), cli_volume(mesh, "ball.stl", params, "rle"));
  EXPECT_EQ(volume(id, "?format=binvox"), cli_volume(mesh, "ball.stl", params, "binvox"));
  EXPECT_EQ(volume(id, "?format=raw"), cli_volume(mesh, "ball.stl", params, "raw"));
  auto streamed = http().Get(("/v1/jobs/" + id + "/volume?format=binvox").c_str());
  ASSERT_TRUE(streamed);
  EXPECT_EQ(streamed->get_header_value("Content-Type"), "application/x-binvox");
  EXPECT_EQ(streamed->get_header_value("Transfer-Encoding"), "chunked");
}

TEST_F(HttpApiTest, RawBodyUploadAsCurlSendsItIsTheSameJobAndIsAnsweredFromTheFinishedResult) {
  start();
  const auto mesh = blob_stl();
  const std::string params = R"({"grid":{"resolution":48}})";
  const json first = submit(mesh, params);
  ASSERT_EQ(wait_for_job(http(), first.at("id")).at("state"), "succeeded");
  // curl --data-binary sends application/x-www-form-urlencoded: a 15 kB mesh
  // must not be parsed (or refused) as a form.
  const json again = expect_json(post_raw(http(), "/v1/jobs", mesh, params), 202, "JobStatus");
  EXPECT_TRUE(again.at("cached"));
  EXPECT_EQ(again.at("state"), "succeeded");
  EXPECT_EQ(again.at("content_hash"), first.at("content_hash"));
  EXPECT_EQ(volume(again.at("id")), volume(first.at("id")));
  // Different parameters are a different job.
  const json other = expect_json(post_raw(http(), "/v1/jobs", mesh, R"({"grid":{"resolution":49}})", "application/octet-stream"), 202,
                                 "JobStatus");
  EXPECT_FALSE(other.at("cached"));
  EXPECT_NE(other.at("content_hash"), first.at("content_hash"));
  EXPECT_EQ(volume(wait_for_job(http(), other.at("id")).at("id")), cli_volume(mesh, "blob.stl", R"({"grid":{"resolution":49}})"));
}

TEST_F(HttpApiTest, CurlAsUsersTypeItMultipartDataBinaryAndCompressed) {
  start();
  const auto mesh = blob_stl();
  const std::string params = R"({"grid":{"resolution":64,"padding":1}})";
  write_file(dir_ + "/blob.stl", mesh);
  std::ofstream(dir_ + "/job.json") << params;
  const std::string base = "http://127.0.0.1:" + std::to_string(server_->port());
  auto r = run_process("curl -sS --fail-with-body -F mesh=@" + dir_ + "/blob.stl -F 'params=<" + dir_ +
                       "/job.json;type=application/json' " + base + "/v1/jobs");
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  schemas_->add("JobStatus", r.out);
  const std::string id = json::parse(r.out).at("id");
  ASSERT_EQ(wait_for_job(http(), id).at("state"), "succeeded");
  r = run_process("curl -sS --fail --compressed -o " + dir_ + "/curl.rle " + base + "/v1/jobs/" + id + "/volume");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(text_of(read_file(dir_ + "/curl.rle")), cli_volume(mesh, "blob.stl", params));
  // --data-binary with params in the query string (curl sends it as a form).
  r = run_process("curl -sS --fail -o " + dir_ + "/sync.binvox --data-binary @" + dir_ + "/blob.stl '" + base +
                  "/v1/voxelize?format=binvox&params=" + url_encode(params) + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(text_of(read_file(dir_ + "/sync.binvox")), cli_volume(mesh, "blob.stl", params, "binvox"));
}

TEST_F(HttpApiTest, EveryMeshFormatIsDetectedFromContentAndMatchesTheCli) {
  if (!draco_encoder_available()) GTEST_FAIL() << "draco_encoder is missing: scripts/install-deps.sh installs it";
  start();
  const Mesh torus = make_torus({0, 0, 0}, 2.0, 0.7, 32, 16);
  const std::map<std::string, std::pair<std::string, std::vector<std::uint8_t>>> uploads = {
      {"stl_ascii", {"t.stl", bytes_of(to_ascii_stl(torus))}},
      {"obj", {"t.obj", bytes_of(to_obj(torus))}},
      {"ply", {"t.ply", to_binary_ply(torus)}},
      {"draco", {"t.drc", encode_with_draco_encoder(torus, "-qp 24")}},
  };
  const std::string params = R"({"grid":{"voxel_size":0.1}})";
  for (const auto& [format, upload] : uploads) {
    // No file name at all: the content decides.
    const json job = expect_json(post_raw(http(), "/v1/jobs", upload.second, params, "application/octet-stream"), 202, "JobStatus");
    EXPECT_EQ(job.at("mesh_format"), format);
    const json done = wait_for_job(http(), job.at("id"));
    ASSERT_EQ(done.at("state"), "succeeded") << done.dump();
    EXPECT_TRUE(done.at("mesh").at("watertight")) << format;
    EXPECT_EQ(volume(done.at("id")), cli_volume(upload.second, upload.first, params)) << format;
  }
}

TEST_F(HttpApiTest, VolumesAreGzippedWhenTheClientAcceptsIt) {
  start();
  const json job = submit(blob_stl(), R"({"grid":{"resolution":96}})");
  wait_for_job(http(), job.at("id"));
  const std::string plain = volume(job.at("id"), "?format=raw");
  http().set_decompress(false);
  auto res = http().Get(("/v1/jobs/" + job.at("id").get<std::string>() + "/volume?format=raw").c_str(),
                        httplib::Headers{{"Accept-Encoding", "gzip"}});
  ASSERT_TRUE(res);
  ASSERT_EQ(res->get_header_value("Content-Encoding"), "gzip");
  EXPECT_LT(res->body.size(), plain.size() / 4);
  // Inflate independently with zlib.
  z_stream z{};
  ASSERT_EQ(inflateInit2(&z, 15 + 16), Z_OK);
  std::string out(plain.size() + 1, '\0');
  z.next_in = reinterpret_cast<Bytef*>(res->body.data());
  z.avail_in = static_cast<uInt>(res->body.size());
  z.next_out = reinterpret_cast<Bytef*>(out.data());
  z.avail_out = static_cast<uInt>(out.size());
  EXPECT_EQ(inflate(&z, Z_FINISH), Z_STREAM_END);
  out.resize(z.total_out);
  inflateEnd(&z);
  EXPECT_EQ(out, plain);
}

TEST_F(HttpApiTest, SynchronousVoxelizeAnswersWithTheVolumeAndRefusesLargeGrids) {
  start({"--sync-max-voxels", "100000"});
  const auto mesh = sphere_stl();
  const std::string params = R"({"grid":{"resolution":32}})";
  auto res = post_multipart(http(), "/v1/voxelize?format=binvox", mesh, "s.stl", params);
  ASSERT_TRUE(res);
  ASSERT_EQ(res->status, 200) << res->body;
  EXPECT_EQ(res->get_header_value("Content-Type"), "application/x-binvox");
  EXPECT_EQ(res->get_header_value("X-Voxd-Dims"), "32,32,32");
  EXPECT_EQ(res->body, cli_volume(mesh, "s.stl", params, "binvox"));
  auto raw = post_raw(http(), "/v1/voxelize", mesh, params);
  ASSERT_TRUE(raw);
  EXPECT_EQ(raw->body, cli_volume(mesh, "s.stl", params, "rle"));
  // 64^3 is over this server's synchronous limit: the client is told where to go.
  const json p = expect_problem(post_raw(http(), "/v1/voxelize", mesh, R"({"grid":{"resolution":64}})"), 422, "limit-exceeded");
  EXPECT_NE(p.at("detail").get<std::string>().find("/v1/jobs"), std::string::npos) << p.dump();
  // Synchronous jobs are not listed.
  EXPECT_EQ(expect_json(http().Get("/v1/jobs"), 200, "JobList").at("total"), 0);
}

TEST_F(HttpApiTest, JobListIsPaginatedNewestFirst) {
  start();
  std::set<std::string> submitted;
  for (int i = 0; i < 5; ++i) submitted.insert(submit(sphere_stl(1.0 + i), R"({"grid":{"resolution":8}})").at("id").get<std::string>());
  std::set<std::string> listed;
  std::string next = "/v1/jobs?limit=2";
  std::string previous_created = "9999";
  int pages = 0;
  while (!next.empty()) {
    const json page = expect_json(http().Get(next.c_str()), 200, "JobList");
    EXPECT_EQ(page.at("total"), 5);
    EXPECT_LE(page.at("jobs").size(), 2u);
    for (const auto& job : page.at("jobs")) {
      EXPECT_TRUE(listed.insert(job.at("id")).second) << "listed twice";
      EXPECT_LE(job.at("created_at").get<std::string>(), previous_created);
      previous_created = job.at("created_at");
    }
    next = page.at("next").is_null() ? "" : page.at("next").get<std::string>();
    ++pages;
  }
  EXPECT_EQ(pages, 3);
  EXPECT_EQ(listed, submitted);
  expect_problem(http().Get("/v1/jobs?limit=0"), 400, "invalid-query");
  expect_problem(http().Get("/v1/jobs?limit=1000"), 400, "invalid-query");
  expect_problem(http().Get("/v1/jobs?offset=-1"), 400, "invalid-query");
  EXPECT_EQ(expect_json(http().Get("/v1/jobs?offset=100"), 200, "JobList").at("jobs").size(), 0u);
}

TEST_F(HttpApiTest, CancellingStopsARunningJobPromptlyAndDeletingRemovesAFinishedOne) {
  start({"--workers", "1"});
  const json slow = submit(blob_stl(), kSlowParams);
  const std::string slow_id = slow.at("id");
  const json queued = submit(sphere_stl(), R"({"grid":{"resolution":16}})");
  const std::string queued_id = queued.at("id");
  wait_for_state(http(), slow_id, "running");
  EXPECT_EQ(wait_for_state(http(), queued_id, "queued").at("state"), "queued");
  expect_problem(http().Get(("/v1/jobs/" + slow_id + "/volume").c_str()), 409, "job-not-finished");

  // A queued job is cancelled at once.
  const json q = expect_json(http().Delete(("/v1/jobs/" + queued_id).c_str()), 202, "JobStatus");
  EXPECT_EQ(q.at("state"), "cancelled");
  // A running one stops within a moment, not at the end of its minutes of work.
  const auto t0 = std::chrono::steady_clock::now();
  auto res = http().Delete(("/v1/jobs/" + slow_id).c_str());
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 202);
  const json cancelled = wait_for_job(http(), slow_id, 20);
  EXPECT_EQ(cancelled.at("state"), "cancelled");
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 10s);

  // The worker is free again for new work.
  const json next = submit(sphere_stl(), R"({"grid":{"resolution":17}})");
  EXPECT_EQ(wait_for_job(http(), next.at("id"), 30).at("state"), "succeeded");
  // Deleting a finished job removes it and its result.
  EXPECT_EQ(http().Delete(("/v1/jobs/" + next.at("id").get<std::string>()).c_str())->status, 204);
  expect_problem(http().Get(("/v1/jobs/" + next.at("id").get<std::string>()).c_str()), 404, "not-found");
  expect_problem(http().Get(("/v1/jobs/" + next.at("id").get<std::string>() + "/volume").c_str()), 404, "not-found");
  expect_problem(http().Delete(("/v1/jobs/" + next.at("id").get<std::string>()).c_str()), 404, "not-found");
  EXPECT_FALSE(std::filesystem::exists(dir_ + "/data/jobs/" + next.at("id").get<std::string>()));
}

TEST_F(HttpApiTest, AFullQueueAnswers429WithRetryAfterAndEveryoneElseIsStillServed) {
  start({"--workers", "1", "--queue-size", "2"});
  const json running = submit(blob_stl(), kSlowParams);
  wait_for_state(http(), running.at("id"), "running");
  std::vector<std::string> queued;
  for (int i = 0; i < 2; ++i) queued.push_back(submit(sphere_stl(1.0 + i), R"({"grid":{"resolution":16}})").at("id"));
  auto res = post_multipart(http(), "/v1/jobs", sphere_stl(5.0), "s.stl", R"({"grid":{"resolution":16}})");
  expect_problem(res, 429, "queue-full");
  const int retry_after = std::stoi(res->get_header_value("Retry-After"));
  EXPECT_GE(retry_after, 1);
  EXPECT_LE(retry_after, 3600);
  // Probes: alive, but not ready for more work.
  EXPECT_EQ(expect_json(http().Get("/healthz"), 200, "Health").at("status"), "ok");
  EXPECT_EQ(expect_json(http().Get("/readyz"), 503, "Health").at("status"), "not ready");
  // Reads are not held up by the queue.
  EXPECT_EQ(expect_json(http().Get("/v1/jobs"), 200, "JobList").at("total"), 3);
  http().Delete(("/v1/jobs/" + running.at("id").get<std::string>()).c_str());
  for (const auto& id : queued) EXPECT_EQ(wait_for_job(http(), id, 30).at("state"), "succeeded");
  EXPECT_EQ(expect_json(http().Get("/readyz"), 200, "Health").at("status"), "ready");
  const std::string metrics = http().Get("/metrics")->body;
  EXPECT_NE(metrics.find("voxd_rejected_requests_total{reason=\"queue-full\"} 1"), std::string::npos) << metrics;
}

TEST_F(HttpApiTest, FinishedJobsSurviveARestartAndUnfinishedOnesAreReportedInterrupted) {
  start({"--workers", "1"});
  const auto mesh = sphere_stl();
  const json done = submit(mesh, R"({"grid":{"resolution":24}})");
  ASSERT_EQ(wait_for_job(http(), done.at("id")).at("state"), "succeeded");
  const std::string before = volume(done.at("id"));
  const json running = submit(blob_stl(), kSlowParams);
  const json queued = submit(sphere_stl(2.0), R"({"grid":{"resolution":24}})");
  wait_for_state(http(), running.at("id"), "running");

  // Killed without warning (a crash, an OOM kill): nothing is lost silently.
  server_.reset();  // SIGKILL
  start({"--workers", "1"});
  const json kept = expect_json(http().Get(("/v1/jobs/" + done.at("id").get<std::string>()).c_str()), 200, "JobStatus");
  EXPECT_EQ(kept.at("state"), "succeeded");
  EXPECT_EQ(kept.at("filled_voxels"), done.at("filled_voxels").is_null() ? kept.at("filled_voxels") : done.at("filled_voxels"));
  EXPECT_EQ(volume(done.at("id")), before);
  for (const json& job : {running, queued}) {
    const json s = expect_json(http().Get(("/v1/jobs/" + job.at("id").get<std::string>()).c_str()), 200, "JobStatus");
    EXPECT_EQ(s.at("state"), "failed") << s.dump();
    EXPECT_EQ(s.at("error").at("type"), "urn:voxd:problem:interrupted") << s.dump();
  }
  // The same submission is accepted again and runs.
  const json again = submit(sphere_stl(2.0), R"({"grid":{"resolution":24}})");
  EXPECT_FALSE(again.at("cached"));
  EXPECT_EQ(wait_for_job(http(), again.at("id")).at("state"), "succeeded");

  // A clean stop (SIGTERM) that gives running jobs no grace: it exits 0 and
  // records the job as interrupted.
  server_->stop();
  server_.reset();
  start({"--workers", "1", "--shutdown-grace", "0"});
  const json slow = submit(blob_stl(), kSlowParams);
  wait_for_state(http(), slow.at("id"), "running");
  EXPECT_EQ(server_->stop(), 0);
  server_.reset();
  start({"--workers", "1"});
  const json after = expect_json(http().Get(("/v1/jobs/" + slow.at("id").get<std::string>()).c_str()), 200, "JobStatus");
  EXPECT_EQ(after.at("state"), "failed");
  EXPECT_EQ(after.at("error").at("type"), "urn:voxd:problem:interrupted");
}

TEST_F(HttpApiTest, ASigtermDrainsAndExitsZero) {
  start({"--shutdown-grace", "0"});
  const json slow = submit(blob_stl(), kSlowParams);
  wait_for_state(http(), slow.at("id"), "running");
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(server_->stop(), 0) << server_->log();
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 15s);
  EXPECT_NE(server_->log().find("stopped"), std::string::npos);
}

TEST_F(HttpApiTest, BadRequestsGetTheirOwnProblemAndTheServiceKeepsServing) {
  start({"--max-upload-bytes", "300000", "--max-triangles", "2000", "--max-voxels", "1000000"});
  const auto mesh = sphere_stl();
  auto post = [&](const std::string& params) { return post_multipart(http(), "/v1/jobs", mesh, "s.stl", params); };

  expect_problem(post(R"({"grid":{"resolution":32})"), 400, "malformed-json");
  json p = expect_problem(post(R"({"grid":{"resolutio":32}})"), 422, "invalid-params");
  EXPECT_EQ(p.at("errors").at(0).at("path"), "/grid/resolutio");
  p = expect_problem(post(R"({"grid":{"resolution":"32"}})"), 422, "invalid-params");
  EXPECT_EQ(p.at("errors").at(0).at("path"), "/grid/resolution");
  p = expect_problem(post(R"({"grid":{"resolution":0},"mode":"soild"})"), 422, "invalid-params");
  EXPECT_EQ(p.at("errors").size(), 2u) << p.dump();
  p = expect_problem(post(R"({"grid":{"resolution":32},"rotation":{"axis":[0,0,0],"angle_deg":10}})"), 422, "invalid-params");
  EXPECT_EQ(p.at("errors").at(0).at("path").get<std::string>().rfind("/rotation", 0), 0u) << p.dump();

  // No mesh part at all is a bad request; an empty mesh file is an empty
  // mesh, answered as the error table (README) and the CLI have it.
  httplib::MultipartFormDataItems only_params = {{"params", "{}", "", "application/json"}};
  expect_problem(http().Post("/v1/jobs", only_params), 400, "missing-mesh");
  for (const auto& empty : {post_raw(http(), "/v1/jobs", {}, "{}", "application/octet-stream"),
                            post_multipart(http(), "/v1/jobs", {}, "empty.stl", "{}")}) {
    p = expect_problem(empty, 422, "invalid-mesh");
    EXPECT_EQ(p.at("detail"), "the mesh file is empty (0 bytes); upload it again") << p.dump();
  }
  const auto cli = run_process(std::string(VOXD_BINARY) + " inspect " + [&] {
    write_file(dir_ + "/empty.stl", {});
    return dir_ + "/empty.stl";
  }());
  EXPECT_EQ(cli.exit_code, 1);
  EXPECT_NE(cli.err.find("the mesh file is empty (0 bytes); upload it again"), std::string::npos) << cli.err;
  // Bad meshes, each with its reason.
  expect_problem(post_raw(http(), "/v1/jobs", bytes_of("hello, this is not a mesh at all\n"), "{}", "application/octet-stream"), 415,
                 "unsupported-format");
  auto truncated = mesh;
  truncated.resize(84 + 50 * 10);
  p = expect_problem(post_raw(http(), "/v1/jobs", truncated, "{}", "application/octet-stream"), 422, "invalid-mesh");
  EXPECT_NE(p.at("detail").get<std::string>().find("cut off"), std::string::npos) << p.dump();
  p = expect_problem(post_raw(http(), "/v1/jobs", bytes_of("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 nan\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid x\n"), "{}", "application/octet-stream"), 422, "invalid-mesh");
  EXPECT_NE(p.at("detail").get<std::string>().find("line 4"), std::string::npos) << p.dump();
  // Limits: bytes (413), triangles and grid size (422).
  expect_problem(post_raw(http(), "/v1/jobs", std::vector<std::uint8_t>(400000, 'x'), "{}", "application/octet-stream"), 413,
                 "upload-too-large");
  expect_problem(post_raw(http(), "/v1/jobs", sphere_stl(1.0, 4), "{}", "application/octet-stream"), 422, "limit-exceeded");
  expect_problem(post(R"({"grid":{"resolution":128}})"), 422, "limit-exceeded");
  // Wrong content type, routes, methods, ids, queries.
  expect_problem(http().Post("/v1/jobs", R"({"grid":{}})", "application/json"), 415, "unsupported-media-type");
  auto wrong_method = http().Put("/v1/jobs", "", "application/octet-stream");
  expect_problem(wrong_method, 405, "method-not-allowed");
  EXPECT_EQ(wrong_method->get_header_value("Allow"), "GET, POST");
  expect_problem(http().Post("/healthz", "", "text/plain"), 405, "method-not-allowed");
  expect_problem(http().Get("/v1/nothing-here"), 404, "not-found");
  expect_problem(http().Get("/v1/jobs/0123456789abcdef0123456789abcdef"), 404, "not-found");
  expect_problem(http().Get("/v1/jobs/not-an-id"), 404, "not-found");
  const json ok = submit(mesh, R"({"grid":{"resolution":16}})");
  wait_for_job(http(), ok.at("id"));
  p = expect_problem(http().Get(("/v1/jobs/" + ok.at("id").get<std::string>() + "/volume?format=vdb").c_str()), 400, "invalid-query");
  EXPECT_NE(p.at("detail").get<std::string>().find("rle"), std::string::npos);

  // After all of that, the service still works for everyone.
  EXPECT_EQ(expect_json(http().Get("/healthz"), 200, "Health").at("status"), "ok");
  const json after = submit(mesh, R"({"grid":{"resolution":20}})");
  EXPECT_EQ(wait_for_job(http(), after.at("id")).at("state"), "succeeded");
  const std::string metrics = http().Get("/metrics")->body;
  EXPECT_NE(metrics.find("voxd_rejected_requests_total{reason=\"invalid-params\"} 4"), std::string::npos) << metrics;
  EXPECT_NE(metrics.find("voxd_rejected_requests_total{reason=\"upload-too-large\"} 1"), std::string::npos) << metrics;
}

TEST_F(HttpApiTest, ASlowOrStalledUploadCannotHoldTheService) {
  start({"--http-threads", "2", "--read-timeout", "1"});
  // Two connections that promise a body and never send it: every HTTP
  // thread is taken until the read timeout frees it.
  std::vector<int> stalled;
  for (int i = 0; i < 2; ++i) {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(static_cast<std::uint16_t>(server_->port()));
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ASSERT_EQ(::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
    const std::string head = "POST /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Type: application/octet-stream\r\nContent-Length: 100000\r\n\r\nsolid";
    ASSERT_EQ(::send(fd, head.data(), head.size(), 0), static_cast<ssize_t>(head.size()));
    stalled.push_back(fd);
  }
  const auto t0 = std::chrono::steady_clock::now();
  auto res = http().Get("/healthz");
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 200);
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 8s);
  for (int fd : stalled) {
    // The server gave up on the stalled upload and closed the connection.
    char buf[4096];
    timeval tv{10, 0};
    ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    ssize_t n;
    while ((n = ::recv(fd, buf, sizeof buf, 0)) > 0) {
    }
    EXPECT_EQ(n, 0) << "connection still open";
    ::close(fd);
  }
}

TEST_F(HttpApiTest, ApiKeysGuardTheV1RoutesButNotTheProbes) {
  start({"--api-keys", "alpha-key,beta-key"});
  auto res = http().Get("/v1/jobs");
  expect_problem(res, 401, "unauthorized");
  EXPECT_EQ(res->get_header_value("WWW-Authenticate"), "Bearer");
  expect_problem(http().Get("/v1/jobs", httplib::Headers{{"Authorization", "Bearer alpha-kez"}}), 401, "unauthorized");
  expect_problem(post_multipart(http(), "/v1/jobs", sphere_stl(), "s.stl", "{}"), 401, "unauthorized");
  expect_json(http().Get("/v1/jobs", httplib::Headers{{"Authorization", "Bearer beta-key"}}), 200, "JobList");
  expect_json(post_multipart(http(), "/v1/jobs", sphere_stl(), "s.stl", R"({"grid":{"resolution":8}})",
                             httplib::Headers{{"Authorization", "Bearer alpha-key"}}),
              202, "JobStatus");
  EXPECT_EQ(http().Get("/healthz")->status, 200);
  EXPECT_EQ(http().Get("/metrics")->status, 200);
}

TEST_F(HttpApiTest, CorsAllowsOnlyTheConfiguredOrigins) {
  start({"--cors-origins", "https://app.example.com"});
  auto pre = http().Options("/v1/jobs", httplib::Headers{{"Origin", "https://app.example.com"},
                                                          {"Access-Control-Request-Method", "POST"}});
  ASSERT_TRUE(pre);
  EXPECT_EQ(pre->status, 204);
  EXPECT_EQ(pre->get_header_value("Access-Control-Allow-Origin"), "https://app.example.com");
  EXPECT_NE(pre->get_header_value("Access-Control-Allow-Methods").find("POST"), std::string::npos);
  auto get = http().Get("/v1/jobs", httplib::Headers{{"Origin", "https://app.example.com"}});
  EXPECT_EQ(get->get_header_value("Access-Control-Allow-Origin"), "https://app.example.com");
  EXPECT_NE(get->get_header_value("Access-Control-Expose-Headers").find("Location"), std::string::npos);
  // A front end on another origin reads a download's file name.
  EXPECT_NE(get->get_header_value("Access-Control-Expose-Headers").find("Content-Disposition"), std::string::npos);
  auto other = http().Get("/v1/jobs", httplib::Headers{{"Origin", "https://evil.example.com"}});
  EXPECT_FALSE(other->has_header("Access-Control-Allow-Origin"));
}

TEST_F(HttpApiTest, MetricsCountJobsRequestsBytesAndStageDurations) {
  start();
  const auto mesh = blob_stl();
  const json job = submit(mesh, R"({"grid":{"resolution":32}})");
  wait_for_job(http(), job.at("id"));
  const std::string vol = volume(job.at("id"));
  expect_problem(post_multipart(http(), "/v1/jobs", mesh, "b.stl", R"({"mode":1})"), 422, "invalid-params");
  // Layer numbers and invented paths count under bounded labels.
  const std::string id = job.at("id");
  for (const char* k : {"999999", "123456"}) http().Get(("/v1/jobs/" + id + "/layers/" + k).c_str());
  http().Get(("/v1/jobs/" + id + "/invented-path").c_str());
  // Metrics are updated just after a job's state or a request's answer is
  // visible (by the job listener and the request logger): poll briefly.
  std::map<std::string, double> values;
  for (int attempt = 0; attempt < 200; ++attempt) {
    auto res = http().Get("/metrics");
    ASSERT_TRUE(res);
    EXPECT_EQ(res->get_header_value("Content-Type").rfind("text/plain; version=0.0.4", 0), 0u);
    values.clear();
    std::istringstream lines(res->body);
    for (std::string line; std::getline(lines, line);) {
      if (line.empty() || line[0] == '#') continue;
      const auto space = line.rfind(' ');
      values[line.substr(0, space)] = std::stod(line.substr(space + 1));
    }
    if (values["voxd_stage_duration_seconds_count{stage=\"voxelize\"}"] == 1 &&
        values["voxd_http_requests_total{method=\"POST\",route=\"/v1/jobs\",status=\"422\"}"] == 1 &&
        values["voxd_http_requests_total{method=\"GET\",route=\"other\",status=\"404\"}"] == 1 &&
        values["voxd_http_requests_total{method=\"GET\",route=\"/v1/jobs/{id}/layers/{k}\",status=\"409\"}"] == 2)
      break;
    std::this_thread::sleep_for(10ms);
  }
  EXPECT_EQ(values["voxd_jobs{state=\"succeeded\"}"], 1);
  EXPECT_EQ(values["voxd_queue_depth"], 0);
  EXPECT_GE(values["voxd_http_bytes_received_total"], 2.0 * static_cast<double>(mesh.size()));
  EXPECT_GE(values["voxd_http_bytes_sent_total"], static_cast<double>(vol.size()));
  EXPECT_EQ(values["voxd_http_requests_total{method=\"POST\",route=\"/v1/jobs\",status=\"202\"}"], 1);
  EXPECT_EQ(values["voxd_http_requests_total{method=\"POST\",route=\"/v1/jobs\",status=\"422\"}"], 1);
  EXPECT_EQ(values["voxd_rejected_requests_total{reason=\"invalid-params\"}"], 1);
  EXPECT_EQ(values["voxd_http_requests_total{method=\"GET\",route=\"/v1/jobs/{id}/layers/{k}\",status=\"409\"}"], 2);
  EXPECT_EQ(values["voxd_http_requests_total{method=\"GET\",route=\"other\",status=\"404\"}"], 1);
  for (const auto& [series, value] : values) EXPECT_EQ(series.find("999999"), std::string::npos) << series;
  EXPECT_EQ(values["voxd_stage_duration_seconds_count{stage=\"voxelize\"}"], 1);
  EXPECT_EQ(values["voxd_stage_duration_seconds_bucket{stage=\"voxelize\",le=\"+Inf\"}"], 1);
  EXPECT_GT(values["voxd_stage_duration_seconds_sum{stage=\"voxelize\"}"], 0);
}

TEST_F(HttpApiTest, TheServedOpenApiDocumentIsTheContractAndEveryDocumentedRouteExists) {
  start();
  auto res = http().Get("/openapi.json");
  ASSERT_TRUE(res);
  ASSERT_EQ(res->status, 200);
  const json served = json::parse(res->body);
  // The repository's document with its schemas embedded (openapi_document_test holds the rest).
  EXPECT_EQ(served["info"], json::parse(text_of(read_file(std::string(VOXD_SOURCE_DIR) + "/proto-schemas/openapi.json")))["info"]);
  EXPECT_TRUE(served["components"]["schemas"]["JobParams"].contains("properties"));
  const json job = submit(sphere_stl(), R"({"grid":{"resolution":8}})");
  wait_for_job(http(), job.at("id"));
  const std::string id = job.at("id");
  int checked = 0;
  for (const auto& [path_template, item] : served.at("paths").items()) {
    const std::string path = std::regex_replace(path_template, std::regex(R"(\{id\})"), id);
    for (const auto& [method, op] : item.items()) {
      if (method == "parameters") continue;  // shared path parameters, not an operation
      if (method == "delete") continue;      // checked by the cancel test; it would remove the job here
      ASSERT_TRUE(method == "get" || method == "post") << "unexpected method " << method;
      const httplib::Result r = method == "get" ? http().Get(path.c_str())
                                                : post_multipart(http(), path, sphere_stl(), "s.stl", R"({"grid":{"resolution":8}})");
      ASSERT_TRUE(r) << method << " " << path;
      EXPECT_TRUE(op.at("responses").contains(std::to_string(r->status)))
          << method << " " << path << " answered " << r->status << ", which the document does not list";
      ++checked;
    }
  }
  EXPECT_GE(checked, 8);
}

TEST_F(HttpApiTest, ManyConcurrentClientsAllGetTheirOwnResults) {
  start();
  std::atomic<int> failures{0};
  std::vector<std::thread> clients;
  std::mutex mutex;
  std::map<std::string, std::uint64_t> expected;  // id -> filled voxels from the engine
  for (int t = 0; t < 6; ++t)
    clients.emplace_back([&, t] {
      auto c = make_client(server_->port());
      for (int i = 0; i < 4; ++i) {
        const Mesh box = make_box({0, 0, 0}, {1.0 + t, 2.0 + i, 1.5});
        auto r = post_multipart(*c, "/v1/jobs", to_binary_stl(box), "b.stl", R"({"grid":{"voxel_size":0.25}})");
        if (!r || r->status != 202) {
          ++failures;
          continue;
        }
        GridRequest g;
        g.kind = GridRequest::Kind::voxel_size;
        g.voxel_size = 0.25;
        const std::uint64_t filled = voxelize(box, resolve_grid(g, bounds(box)), {}).count();
        std::lock_guard lock(mutex);
        expected[json::parse(r->body).at("id")] = filled;
      }
    });
  for (auto& c : clients) c.join();
  EXPECT_EQ(failures, 0);
  ASSERT_EQ(expected.size(), 24u);
  for (const auto& [id, filled] : expected) {
    const json done = wait_for_job(http(), id);
    ASSERT_EQ(done.at("state"), "succeeded");
    EXPECT_EQ(done.at("filled_voxels").get<std::uint64_t>(), filled) << id;
  }
}

TEST_F(HttpApiTest, EveryRequestAndJobStateIsLoggedAndJsonLogsAreJson) {
  start({"--log-format", "json"}, {"VOXD_WORKERS=1"});
  auto res = http().Get("/healthz", httplib::Headers{{"X-Request-Id", "trace-me-42"}});
  EXPECT_EQ(res->get_header_value("X-Request-Id"), "trace-me-42");
  const json job = submit(sphere_stl(), R"({"grid":{"resolution":8}})");
  wait_for_job(http(), job.at("id"));
  std::this_thread::sleep_for(100ms);
  bool request_line = false;
  std::set<std::string> states;
  std::istringstream lines(server_->log());
  for (std::string line; std::getline(lines, line);) {
    const json entry = json::parse(line);  // every line is JSON
    const json message = entry.at("message");
    if (message.is_object() && message.value("event", "") == "request" && message.at("request_id") == "trace-me-42") {
      request_line = message.at("method") == "GET" && message.at("path") == "/healthz" && message.at("status") == 200 &&
                     message.contains("duration_ms") && message.contains("bytes");
    }
    if (message.is_object() && message.value("event", "") == "job" && message.at("id") == job.at("id"))
      states.insert(message.at("state").get<std::string>());
  }
  EXPECT_TRUE(request_line) << server_->log();
  EXPECT_EQ(states, (std::set<std::string>{"queued", "running", "succeeded"})) << server_->log();
}

TEST_F(HttpApiTest, AnalysisOfAHollowBoxFindsItsVoidItsThinWallsAndIsKept) {
  start();
  // Walls 2 to 4 voxels thick around a 5 x 5 x 4 cavity, on a unit grid.
  const Mesh m = concat({make_box({1, 1, 1}, {11, 11, 11}), flipped(make_box({3, 4, 5}, {8, 9, 9}))});
  const json job = submit(to_binary_stl(m), R"({"grid":{"voxel_size":1,"origin":[0,0,0],"dims":[12,12,12]}})");
  const std::string id = job.at("id");
  ASSERT_EQ(wait_for_job(http(), id).at("state"), "succeeded");
  auto first = http().Get(("/v1/jobs/" + id + "/analysis?min_wall=2.5").c_str());
  const json a = expect_json(first, 200, "Analysis");
  EXPECT_EQ(first->get_header_value("X-Voxd-Cache"), "miss");
  EXPECT_EQ(a.at("parts").at("count"), 1);
  EXPECT_EQ(a.at("voids").at("count"), 1);
  EXPECT_EQ(a.at("voids").at("total_volume"), 100.0);
  EXPECT_TRUE(a.at("mass_properties").at("mesh").at("available"));
  EXPECT_NEAR(a.at("mass_properties").at("mesh").at("volume").get<double>(), 900.0, 1e-9);
  const json& t = a.at("thickness");
  // The 2-voxel walls. Exact on walls whose faces are flat for two voxels
  // around (the surface fits' windows); every face of this small box is
  // nearer an edge than that, where the fits lean: within a quarter voxel.
  EXPECT_NEAR(t.at("min").get<double>(), 2.0, 0.25);
  // Half a voxel under min_wall is within the error bound (a voxel): the
  // walls there may be either side, and a voxel of 0.4 would decide them.
  EXPECT_EQ(t.at("verdict"), "inconclusive");
  EXPECT_GE(t.at("thin_regions").at("count").get<int>(), 1);
  EXPECT_EQ(t.at("thin_regions").at("marginal"), t.at("thin_regions").at("count"));
  EXPECT_NEAR(t.at("voxel_size_to_decide").get<double>(), 0.4, 0.2);
  EXPECT_NE(t.at("verdict_reason").get<std::string>().find("would decide it"), std::string::npos);
  EXPECT_FALSE(t.at("error_bound").get<std::string>().empty());
  // Kept: the same answer from the job's directory.
  auto again = http().Get(("/v1/jobs/" + id + "/analysis?min_wall=2.5").c_str());
  EXPECT_EQ(again->get_header_value("X-Voxd-Cache"), "hit");
  EXPECT_EQ(again->body, first->body);
  // Two voxels under min_wall: thin beyond the bound; a voxel over: sound.
  const json fail = expect_json(http().Get(("/v1/jobs/" + id + "/analysis?min_wall=4").c_str()), 200, "Analysis");
  EXPECT_EQ(fail.at("thickness").at("verdict"), "fail");
  EXPECT_EQ(fail.at("thickness").at("thin_regions").at("items").at(0).at("certain"), true);
  EXPECT_TRUE(fail.at("thickness").at("voxel_size_to_decide").is_null());
  EXPECT_EQ(expect_json(http().Get(("/v1/jobs/" + id + "/analysis?min_wall=1").c_str()), 200, "Analysis")
                .at("thickness").at("verdict"), "pass");
  EXPECT_TRUE(expect_json(http().Get(("/v1/jobs/" + id + "/analysis?thickness=false").c_str()), 200, "Analysis")
                  .at("thickness").is_null());
  expect_problem(http().Get(("/v1/jobs/" + id + "/analysis?min_wall=-1").c_str()), 400, "invalid-query");
  expect_problem(http().Get(("/v1/jobs/" + id + "/analysis?cleanup=all").c_str()), 400, "invalid-query");
}

TEST_F(HttpApiTest, RadiographyAndSectionImagesCarryExactValuesAndTheirScale) {
  start();
  // Box over voxels x 4..13, y 2..7, z 6..21 of a 0.5 grid.
  const json job = submit(to_binary_stl(make_box({2, 1, 3}, {7, 4, 11})),
                          R"({"grid":{"voxel_size":0.5,"origin":[0,0,0],"dims":[20,12,30]}})");
  const std::string id = job.at("id");
  ASSERT_EQ(wait_for_job(http(), id).at("state"), "succeeded");
  auto res = http().Get(("/v1/jobs/" + id + "/radiography?axis=z&measure=total&format=png16&unit=model").c_str());
  ASSERT_TRUE(res);
  ASSERT_EQ(res->status, 200) << res->body;
  EXPECT_EQ(res->get_header_value("Content-Type"), "image/png");
  EXPECT_EQ(res->get_header_value("X-Voxd-Scale"), "1 pixel value = 0.5 model units");
  json png = read_png(res->body);
  EXPECT_EQ(png.at("width"), 20);
  EXPECT_EQ(png.at("height"), 12);
  EXPECT_EQ(png.at("bit_depth"), 16);
  EXPECT_EQ(png.at("text").at("voxd:scale"), "1 pixel value = 0.5 model units");
  for (int j = 0; j < 12; ++j)
    for (int i = 0; i < 20; ++i) {
      const bool inside = i >= 4 && i < 14 && j >= 2 && j < 8;
      ASSERT_EQ(png.at("pixels").at(j * 20 + i), inside ? 16 : 0) << i << "," << j;
    }
  // Along x: image columns are y, rows are z.
  png = read_png(http().Get(("/v1/jobs/" + id + "/radiography?axis=x&measure=max").c_str())->body);
  EXPECT_EQ(png.at("width"), 12);
  EXPECT_EQ(png.at("height"), 30);
  EXPECT_EQ(png.at("pixels").at(10 * 12 + 3), 10);
  // False colour for people, statistics for programs.
  png = read_png(http().Get(("/v1/jobs/" + id + "/radiography?axis=y&format=png").c_str())->body);
  EXPECT_EQ(png.at("color_type"), 2);
  EXPECT_GT(png.at("height").get<int>(), 30);  // the legend strip below the map
  const json stats = expect_json(http().Get(("/v1/jobs/" + id + "/radiography?axis=y&format=json&unit=model").c_str()), 200,
                                 "RadiographyStats");
  EXPECT_EQ(stats.at("rays"), 10 * 16);
  EXPECT_EQ(stats.at("min"), 3.0);  // 6 voxels of 0.5
  EXPECT_EQ(stats.at("max"), 3.0);
  // Section through the box at model z = 5 (voxel layer 10), and by index.
  auto sec = http().Get(("/v1/jobs/" + id + "/section?axis=z&coordinate=5.2").c_str());
  ASSERT_EQ(sec->status, 200) << sec->body;
  png = read_png(sec->body);
  EXPECT_EQ(png.at("text").at("voxd:index"), "10");
  std::uint64_t filled = 0;
  for (const auto& v : png.at("pixels")) filled += v.get<int>() == 255;
  EXPECT_EQ(filled, 60u);
  EXPECT_EQ(http().Get(("/v1/jobs/" + id + "/section?axis=z&index=10").c_str())->body, sec->body);
  png = read_png(http().Get(("/v1/jobs/" + id + "/section?axis=z&index=2").c_str())->body);
  for (const auto& v : png.at("pixels")) ASSERT_EQ(v, 0);
  // After one peel of skin the 10 x 6 section is 8 x 4; two Euclidean peels leave 6 x 2.
  for (const auto& [query, want] : {std::pair<std::string, int>{"peel=1", 32}, {"peel=2&peel_metric=euclidean", 12}}) {
    png = read_png(http().Get(("/v1/jobs/" + id + "/section?axis=z&index=10&" + query).c_str())->body);
    int n = 0;
    for (const auto& v : png.at("pixels")) n += v.get<int>() == 255;
    EXPECT_EQ(n, want) << query;
    EXPECT_FALSE(png.at("text").at("voxd:peeled").get<std::string>().empty());
  }
  // Radiography after one peel: the ray through the middle crosses 16 - 2 voxels.
  png = read_png(http().Get(("/v1/jobs/" + id + "/radiography?axis=z&measure=total&peel=1").c_str())->body);
  EXPECT_EQ(png.at("pixels").at(4 * 20 + 8), 14);
  EXPECT_EQ(png.at("pixels").at(2 * 20 + 4), 0);  // the skin's corner ray is empty now
  // Bad queries, unknown jobs, unfinished jobs, wrong methods.
  expect_problem(http().Get(("/v1/jobs/" + id + "/radiography?axis=w").c_str()), 400, "invalid-query");
  expect_problem(http().Get(("/v1/jobs/" + id + "/radiography?measure=average").c_str()), 400, "invalid-query");
  expect_problem(http().Get(("/v1/jobs/" + id + "/section?axis=z").c_str()), 400, "invalid-query");
  expect_problem(http().Get(("/v1/jobs/" + id + "/section?axis=z&index=30").c_str()), 400, "invalid-query");
  expect_problem(http().Get(("/v1/jobs/" + id + "/section?axis=z&coordinate=99").c_str()), 400, "invalid-query");
  expect_problem(http().Get("/v1/jobs/0123456789abcdef0123456789abcdef/radiography"), 404, "not-found");
  expect_problem(http().Delete(("/v1/jobs/" + id + "/section").c_str()), 405, "method-not-allowed");
  const json slow = submit(blob_stl(), kSlowParams);
  wait_for_state(http(), slow.at("id"), "running");
  expect_problem(http().Get(("/v1/jobs/" + slow.at("id").get<std::string>() + "/analysis").c_str()), 409, "job-not-finished");
  http().Delete(("/v1/jobs/" + slow.at("id").get<std::string>()).c_str());
}

// A large answer computed just now is sent while it is written (the write
// and its sync take as long as computing it): the client gets every byte,
// the service logs their count, and a second request, which waits for the
// write, is answered from the kept result with the same bytes.
TEST_F(HttpApiTest, ALargeThicknessVolumeIsSentWhileItIsKeptAndThenServedKept) {
  start();
  // A plate 4 voxels thick (z voxels 1..4) over x, y voxels 1..256: a raw
  // volume of 258 x 258 x 34 floats, 9 MB, over the 8 MiB from which
  // answers are kept while they are sent.
  const json job = submit(to_binary_stl(make_box({0.5, 0.5, 0.5}, {128.5, 128.5, 2.5})),
                          R"({"grid":{"voxel_size":0.5,"origin":[0,0,0],"dims":[258,258,34]}})");
  const std::string id = job.at("id");
  ASSERT_EQ(wait_for_job(http(), id).at("state"), "succeeded");
  const std::string path = "/v1/jobs/" + id + "/thickness?format=raw&unit=voxels";
  auto first = http().Get(path.c_str());
  ASSERT_EQ(first->status, 200) << first->body;
  EXPECT_EQ(first->get_header_value("X-Voxd-Cache"), "miss");
  const std::size_t voxels = 258u * 258u * 34u;
  ASSERT_EQ(first->body.size(), voxels * 4);
  EXPECT_EQ(first->get_header_value("Content-Length"), std::to_string(voxels * 4));
  const std::vector<float> values = floats_of(first->body);
  for (std::size_t k = 0; k < 34; ++k)
    for (std::size_t j = 0; j < 258; ++j)
      for (std::size_t i = 0; i < 258; ++i) {
        const bool in = i >= 1 && i <= 256 && j >= 1 && j <= 256 && k >= 1 && k <= 4;
        ASSERT_EQ(values[i + 258 * (j + 258 * k)], in ? 4.0f : 0.0f) << i << "," << j << "," << k;
      }
  auto again = http().Get(path.c_str());
  ASSERT_EQ(again->status, 200);
  EXPECT_EQ(again->get_header_value("X-Voxd-Cache"), "hit");
  EXPECT_TRUE(again->body == first->body);
  EXPECT_NE(server_->log().find("/thickness 200 " + std::to_string(voxels * 4) + "B"), std::string::npos);
}

TEST_F(HttpApiTest, PreviewThicknessVolumeAndThicknessSectionsDescribeThePart) {
  start();
  // A plate 4 voxels thick (z voxels 1..4) over x, y voxels 1..18, voxel 0.5
  // (wide enough for the images' legend strip).
  const json job = submit(to_binary_stl(make_box({0.5, 0.5, 0.5}, {9.5, 9.5, 2.5})),
                          R"({"grid":{"voxel_size":0.5,"origin":[0,0,0],"dims":[20,20,6]}})");
  const std::string id = job.at("id");
  ASSERT_EQ(wait_for_job(http(), id).at("state"), "succeeded");
  auto voxel = [](int i, int j, int k) { return static_cast<std::size_t>(i + 20 * (j + 20 * k)); };

  // The thickness volume: NRRD in model units by default. A plate of even
  // thickness reports it exactly (4 voxels = 2 model units) at every voxel.
  auto res = http().Get(("/v1/jobs/" + id + "/thickness").c_str());
  ASSERT_EQ(res->status, 200) << res->body;
  EXPECT_EQ(res->get_header_value("Content-Type"), "application/x-nrrd");
  EXPECT_EQ(res->get_header_value("X-Voxd-Dims"), "20 20 6");
  EXPECT_EQ(res->get_header_value("X-Voxd-Unit"), "model units");
  EXPECT_EQ(res->get_header_value("X-Voxd-Cache"), "miss");
  const Nrrd nrrd = parse_nrrd(res->body);
  const std::vector<float> values = floats_of(nrrd.data);
  EXPECT_EQ(nrrd.fields.at("type"), "float");
  EXPECT_EQ(nrrd.fields.at("sizes"), "20 20 6");
  EXPECT_EQ(nrrd.fields.at("space directions"), "(0.5,0,0) (0,0.5,0) (0,0,0.5)");
  EXPECT_EQ(nrrd.fields.at("space origin"), "(0.25,0.25,0.25)");
  EXPECT_EQ(nrrd.fields.at("endian"), "little");
  ASSERT_EQ(values.size(), 20u * 20 * 6);
  for (int k = 0; k < 6; ++k)
    for (int j = 0; j < 20; ++j)
      for (int i = 0; i < 20; ++i) {
        const bool in = i >= 1 && i <= 18 && j >= 1 && j <= 18 && k >= 1 && k <= 4;
        // The wall between the plate's faces, 4 voxels, rim and corners included.
        ASSERT_EQ(values[voxel(i, j, k)], in ? 2.0f : 0.0f) << i << "," << j << "," << k;
      }
  EXPECT_EQ(http().Get(("/v1/jobs/" + id + "/thickness").c_str())->get_header_value("X-Voxd-Cache"), "hit");
  auto raw = http().Get(("/v1/jobs/" + id + "/thickness?format=raw&unit=voxels").c_str());
  ASSERT_EQ(raw->body.size(), 20u * 20 * 6 * 4);
  float v = 0;
  std::memcpy(&v, raw->body.data() + voxel(5, 5, 2) * 4, 4);
  EXPECT_EQ(v, 4.0f);
  // RLE (value_type f32), decoded by the independent reader.
  auto rle = http().Get(("/v1/jobs/" + id + "/thickness?format=rle").c_str());
  write_file(dir_ + "/t.rle", bytes_of(rle->body));
  const auto decoded = run_process("/usr/bin/python3 " + std::string(VOXD_SOURCE_DIR) + "/tests/tools/read_rle.py " + dir_ +
                                   "/t.rle " + dir_ + "/t.f32");
  ASSERT_EQ(decoded.exit_code, 0) << decoded.err;
  EXPECT_EQ(text_of(read_file(dir_ + "/t.f32")), nrrd.data);
  expect_problem(http().Get(("/v1/jobs/" + id + "/thickness?format=vtk").c_str()), 400, "invalid-query");
  expect_problem(http().Get(("/v1/jobs/" + id + "/thickness?measure=bonej").c_str()), 400, "invalid-query");
  // BoneJ's local thickness stays as a named measure, computed and kept
  // apart from the wall thickness.
  auto local = http().Get(("/v1/jobs/" + id + "/thickness?measure=local").c_str());
  ASSERT_EQ(local->status, 200) << local->body;
  const Nrrd local_nrrd = parse_nrrd(local->body);
  EXPECT_EQ(local_nrrd.fields.at("content"), "local thickness (model units)");
  const std::vector<float> local_values = floats_of(local_nrrd.data);
  ASSERT_EQ(local_values.size(), values.size());
  EXPECT_EQ(local_values[voxel(9, 9, 2)], 2.0f);
  EXPECT_NE(server_->log().find("job " + id + ": local thickness computed"), std::string::npos);
  EXPECT_EQ(nrrd.fields.at("content"), "wall thickness (model units)");

  // Preview from +z ('+' escaped, and unescaped, which a query decodes to a
  // space): the plate's footprint, shaded, on white.
  auto pre = http().Get(("/v1/jobs/" + id + "/preview?view=%2Bz").c_str());
  ASSERT_EQ(pre->status, 200) << pre->body;
  EXPECT_EQ(pre->get_header_value("Content-Type"), "image/png");
  json png = read_png(pre->body);
  EXPECT_EQ(png.at("width"), 20);
  EXPECT_EQ(png.at("height"), 20);
  EXPECT_EQ(png.at("color_type"), 2);
  EXPECT_EQ(png.at("text").at("voxd:view"), "+z");
  EXPECT_EQ(http().Get(("/v1/jobs/" + id + "/preview?view=+z").c_str())->body, pre->body);
  const json& px = png.at("pixels");
  auto white = [&](int c, int r) {
    const std::size_t p = 3 * static_cast<std::size_t>(r * 20 + c);
    return px.at(p) == 255 && px.at(p + 1) == 255 && px.at(p + 2) == 255;
  };
  EXPECT_TRUE(white(0, 0));
  EXPECT_FALSE(white(5, 5));
  int part = 0;
  for (int r = 0; r < 20; ++r)
    for (int c = 0; c < 20; ++c) part += !white(c, r);
  EXPECT_EQ(part, 18 * 18);
  png = read_png(http().Get(("/v1/jobs/" + id + "/preview?view=-x&colour=thickness").c_str())->body);
  EXPECT_EQ(png.at("width"), 20);
  EXPECT_GT(png.at("height").get<int>(), 6);  // the legend under the 20 x 6 view
  expect_problem(http().Get(("/v1/jobs/" + id + "/preview?view=up").c_str()), 400, "invalid-query");
  expect_problem(http().Get(("/v1/jobs/" + id + "/preview?angle=30").c_str()), 400, "invalid-query");

  // A front end asking for three thickness images of a fresh job at once
  // gets them all from one wall-thickness computation.
  const std::string id2 = submit(to_binary_stl(make_box({0.5, 0.5, 0.5}, {9.5, 9.5, 2.5})),
                                 R"({"grid":{"voxel_size":0.5,"origin":[0,0,0],"dims":[20,20,7]}})")
                              .at("id");
  ASSERT_EQ(wait_for_job(http(), id2).at("state"), "succeeded");
  std::vector<std::thread> clients;
  std::atomic<int> ok{0};
  for (const char* route : {"/preview?view=-z&colour=thickness", "/section?axis=x&index=4&colour=thickness",
                            "/thickness?format=raw", "/analysis"}) {
    clients.emplace_back([&, route] {
      auto client = make_client(server_->port());
      auto r = client->Get(("/v1/jobs/" + id2 + route).c_str());
      ok += r && r->status == 200;
    });
  }
  for (auto& c : clients) c.join();
  EXPECT_EQ(ok.load(), 4);
  const std::string log = server_->log();
  std::size_t computed = 0;
  for (std::size_t at = log.find("job " + id2 + ": wall thickness computed"); at != std::string::npos;
       at = log.find("job " + id2 + ": wall thickness computed", at + 1))
    ++computed;
  EXPECT_EQ(computed, 1u) << log;

  // Section coloured by thickness: RGB with a legend, grey without.
  png = read_png(http().Get(("/v1/jobs/" + id + "/section?axis=z&index=2&colour=thickness").c_str())->body);
  EXPECT_EQ(png.at("color_type"), 2);
  EXPECT_GT(png.at("height").get<int>(), 20);
  png = read_png(http().Get(("/v1/jobs/" + id + "/section?axis=z&index=2").c_str())->body);
  EXPECT_EQ(png.at("color_type"), 0);
}

TEST_F(HttpApiTest, AnalysesInTheJobJsonArePreparedByTheWorkerAndServedAsKept) {
  start();
  const json job = submit(to_binary_stl(make_box({1, 1, 1}, {9, 9, 4})),
                          R"({"grid":{"voxel_size":1,"origin":[0,0,0],"dims":[10,10,6]},
                              "analyses":[{"kind":"analysis","min_wall":4.5},
                                          {"kind":"preview","view":"-x","colour":"thickness"},
                                          {"kind":"section","axis":"z","index":99},
                                          {"kind":"thickness","format":"raw","unit":"voxels"},
                                          {"kind":"radiography","axis":"x","measure":"total","format":"json"}]})");
  const std::string id = job.at("id");
  ASSERT_EQ(job.at("analyses").size(), 5u);
  EXPECT_EQ(job.at("analyses").at(0).at("state"), "pending");
  const json done = wait_for_job(http(), id);
  ASSERT_EQ(done.at("state"), "succeeded");
  schemas_->add("JobStatus", done.dump());
  const json& a = done.at("analyses");
  ASSERT_EQ(a.size(), 5u);
  EXPECT_EQ(a.at(0).at("url"), "/v1/jobs/" + id + "/analysis?cleanup=none&thickness=true&min_wall=4.5");
  EXPECT_EQ(a.at(1).at("url"), "/v1/jobs/" + id + "/preview?view=-x&colour=thickness");
  EXPECT_EQ(a.at(2).at("state"), "failed");
  EXPECT_NE(a.at(2).at("error").get<std::string>().find("index must be an integer from 0 to 5"), std::string::npos)
      << a.dump();
  for (int i : {0, 1, 3, 4}) {
    SCOPED_TRACE(a.at(i).dump());
    EXPECT_EQ(a.at(i).at("state"), "ready");
    EXPECT_TRUE(a.at(i).at("error").is_null());
    auto res = http().Get(a.at(i).at("url").get<std::string>().c_str());
    ASSERT_EQ(res->status, 200) << res->body;
    EXPECT_EQ(res->get_header_value("X-Voxd-Cache"), "hit");  // the worker's bytes
  }
  // The worker's analysis is the route's: a 3-voxel plate (reported as 4,
  // see voxd/analysis/local_thickness.h) fails a 4.5-unit minimum wall.
  const json analysis = expect_json(http().Get(a.at(0).at("url").get<std::string>().c_str()), 200, "Analysis");
  EXPECT_EQ(analysis.at("thickness").at("verdict"), "fail");
  const json stats = expect_json(http().Get(a.at(4).at("url").get<std::string>().c_str()), 200, "RadiographyStats");
  EXPECT_EQ(stats.at("max"), 8.0);
  // Its record survives a restart.
  server_->stop();
  start();
  EXPECT_EQ(expect_json(http().Get(("/v1/jobs/" + id).c_str()), 200, "JobStatus").at("analyses"), a);

  // Bad analyses are refused at submission, each with its JSON pointer.
  json p = expect_problem(post_multipart(http(), "/v1/jobs", to_binary_stl(make_box({1, 1, 1}, {2, 2, 2})), "b.stl",
                                         R"({"analyses":[{"kind":"radiography","axis":"w"},{"kind":"hologram"},
                                                         {"kind":"section","axis":"z"},{"kind":"preview","zoom":2}]})"),
                          422, "invalid-params");
  std::set<std::string> paths;
  for (const auto& e : p.at("errors")) paths.insert(e.at("path"));
  EXPECT_EQ(paths, (std::set<std::string>{"/analyses/0/axis", "/analyses/1/kind", "/analyses/2/index", "/analyses/3/zoom"}))
      << p.dump();
  p = expect_problem(post_multipart(http(), "/v1/voxelize", to_binary_stl(make_box({1, 1, 1}, {2, 2, 2})), "b.stl",
                                    R"({"analyses":[{"kind":"preview"}]})"),
                     422, "invalid-params");
  EXPECT_EQ(p.at("errors").at(0).at("path"), "/analyses");
}

TEST(ServeCommand, HelpListsEverySettingWithItsDefaultAndBadSettingsAreRefused) {
  const auto help = run_process(std::string(VOXD_BINARY) + " serve --help");
  EXPECT_EQ(help.exit_code, 0);
  for (const char* flag : {"--host", "--port", "--workers", "--queue-size", "--data-dir", "--max-upload-bytes", "--max-triangles",
                           "--max-voxels", "--result-ttl", "--cors-origins", "--api-keys", "--log-format", "--read-timeout"})
    EXPECT_NE(help.out.find(flag), std::string::npos) << flag;
  EXPECT_NE(help.out.find("VOXD_PORT"), std::string::npos);
  EXPECT_NE(help.out.find("[default: 8080]"), std::string::npos);
  const auto bad = run_process(std::string(VOXD_BINARY) + " serve --workers many");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--workers"), std::string::npos) << bad.err;
  const auto unknown = run_process(std::string(VOXD_BINARY) + " serve --colour red");
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_NE(unknown.err.find("--colour"), std::string::npos) << unknown.err;
  const auto env = run_process("VOXD_QUEUE_SIZE=-3 " + std::string(VOXD_BINARY) + " serve");
  EXPECT_EQ(env.exit_code, 2);
  EXPECT_NE(env.err.find("VOXD_QUEUE_SIZE"), std::string::npos) << env.err;
}

}  // namespace
}  // namespace voxd::test
