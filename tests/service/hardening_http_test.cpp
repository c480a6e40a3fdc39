// Requests an attacker would send, against a real `voxd serve` on loopback
// (issue #12's findings, each reproducer generated here). Every test checks
// the clean answer (a 4xx/503 problem, or a closed connection where HTTP has
// no answer), where it matters that the server's peak memory stayed bounded,
// and that the service then still finishes a normal job.
#include <atomic>
#include <chrono>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <zlib.h>

#include "support/draco_cli.h"
#include "support/http_fixture.h"
#include "support/ply_writer.h"
#include "support/raw_socket.h"

namespace voxd::test {
namespace {

using namespace std::chrono_literals;
using nlohmann::json;

class Hardening : public HttpServiceTest {
 protected:
  // /healthz answers and a small job succeeds, the same as on a fresh server.
  void expect_healthy() {
    auto health = http().Get("/healthz");
    ASSERT_TRUE(health);
    EXPECT_EQ(health->status, 200);
    // A queue a test filled may need a moment to drain: 429s are retried.
    const auto until = std::chrono::steady_clock::now() + 60s;
    auto post = [&] {
      return post_multipart(http(), "/v1/jobs", to_binary_stl(make_box({0, 0, 0}, {1, 2, 3})), "part.stl",
                            R"({"grid": {"resolution": 16}})");
    };
    httplib::Result res = post();
    while (res && res->status == 429 && std::chrono::steady_clock::now() < until) {
      std::this_thread::sleep_for(200ms);
      res = post();
    }
    finished(expect_json(res, 202, "JobStatus"));
  }

  // The server's peak memory grew by less than `bytes` since `before`.
  void expect_peak_growth_below(std::uint64_t before, std::uint64_t bytes) {
    const std::uint64_t after = server_->peak_rss();
    EXPECT_LT(after - before, bytes) << "peak RSS went from " << (before >> 20) << " MiB to " << (after >> 20) << " MiB";
  }

  // A small job first, so the peak includes what any job costs.
  std::uint64_t warm_peak() {
    expect_healthy();
    return server_->peak_rss();
  }
};

std::string nested_arrays(std::size_t depth, const std::string& inner = "1") {
  return std::string(depth, '[') + inner + std::string(depth, ']');
}

std::string gzip_bytes(const std::string& data) {
  z_stream z{};
  deflateInit2(&z, 1, Z_DEFLATED, 31, 8, Z_DEFAULT_STRATEGY);
  std::string out(deflateBound(&z, data.size()), '\0');
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(data.data()));
  z.avail_in = static_cast<uInt>(data.size());
  z.next_out = reinterpret_cast<Bytef*>(out.data());
  z.avail_out = static_cast<uInt>(out.size());
  deflate(&z, Z_FINISH);
  out.resize(z.total_out);
  deflateEnd(&z);
  return out;
}

// Finding 2: 60,000 levels of nesting in each place whose error message used
// to serialize the value recursively.
TEST_F(Hardening, DeeplyNestedParamsAreRefusedNotACrash) {
  start();
  const std::string deep = nested_arrays(60000);
  for (const std::string& params :
       {R"({"mode": "coverage", "coverage": {"seed": )" + deep + "}}", R"({"grid": {"voxel_size": 1, "origin": )" + deep +
                                                                          R"(, "dims": [4, 4, 4]}})",
        R"({"mode": "slice", "slice": {"function": "single_color", "color": )" + deep + "}}"}) {
    const json p = expect_problem(post_multipart(http(), "/v1/jobs", to_binary_stl(make_box({0, 0, 0}, {1, 1, 1})),
                                                 "part.stl", params),
                                  400, "malformed-json");
    EXPECT_NE(p.at("detail").get<std::string>().find("levels deep"), std::string::npos) << p.dump();
  }
  // In the query string of a raw upload too (within httplib's URI limit).
  expect_problem(post_raw(http(), "/v1/voxelize", to_binary_stl(make_box({0, 0, 0}, {1, 1, 1})),
                          R"({"grid": {"resolution": )" + nested_arrays(600) + "}}"),
                 400, "malformed-json");
  expect_healthy();
}

TEST_F(Hardening, DeeplyNestedParamsAreAUsageErrorInTheCli) {
  const std::string dir = make_temp_dir("voxd-deep");
  write_file(dir + "/box.stl", to_binary_stl(make_box({0, 0, 0}, {1, 1, 1})));
  std::ofstream(dir + "/params.json") << R"({"coverage": {"seed": )" << nested_arrays(60000) << "}}";
  const auto r = run_process(std::string(VOXD_BINARY) + " voxelize " + dir + "/box.stl -o " + dir +
                             "/out.rle --params @" + dir + "/params.json");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("levels deep"), std::string::npos) << r.err;
  std::filesystem::remove_all(dir);
}

// Finding 12: a number beyond a double is malformed JSON, not an internal error.
TEST_F(Hardening, NumberBeyondADoubleIsMalformedJson) {
  start();
  const json p = expect_problem(
      post_multipart(http(), "/v1/jobs", to_binary_stl(make_box({0, 0, 0}, {1, 1, 1})), "part.stl",
                     R"({"grid": {"voxel_size": 1e400}})"),
      400, "malformed-json");
  EXPECT_NE(p.at("detail").get<std::string>().find("1e400"), std::string::npos) << p.dump();
  expect_healthy();
}

// Finding 6: the params part has a limit of its own, enforced while it
// streams in, and the refused rest of the body is never read as requests.
TEST_F(Hardening, OversizedParamsPartIsRefusedWhileItStreams) {
  start();
  const std::uint64_t before = warm_peak();
  const std::string boundary = "voxdboundary";
  const std::string mesh = text_of(to_binary_stl(make_box({0, 0, 0}, {1, 1, 1})));
  std::string params(200u << 20, '1');  // 200 MB of JSON: one number in an array
  params.front() = '[';
  params.back() = ']';
  const std::string body = "--" + boundary + "\r\nContent-Disposition: form-data; name=\"mesh\"; filename=\"a.stl\"\r\n\r\n" +
                           mesh + "\r\n--" + boundary +
                           "\r\nContent-Disposition: form-data; name=\"params\"\r\n\r\n" + params + "\r\n--" + boundary +
                           "--\r\n";
  RawSocket s(server_->port());
  s.send("POST /v1/jobs HTTP/1.1\r\nHost: t\r\nContent-Type: multipart/form-data; boundary=" + boundary +
         "\r\nContent-Length: " + std::to_string(body.size()) + "\r\n\r\n");
  std::thread sender([&] { s.send(body); });  // fails once the server closes
  bool closed = false;
  const std::string answer = s.read_until_closed(30s, &closed);
  sender.join();
  EXPECT_TRUE(closed);
  EXPECT_EQ(answer.rfind("HTTP/1.1 413", 0), 0u) << answer.substr(0, 300);
  EXPECT_NE(answer.find("params-too-large"), std::string::npos) << answer.substr(0, 600);
  expect_peak_growth_below(before, std::uint64_t{96} << 20);
  expect_healthy();
}

// Finding 3: after a 413 on a gzip body, the connection closes: a request
// hidden in the rest of the body is never answered.
TEST_F(Hardening, NoRequestIsSmuggledBehindARefusedGzipBody) {
  start({"--max-upload-bytes", "1000000"});
  const std::string smuggled = "GET /healthz HTTP/1.1\r\nHost: t\r\n\r\n";
  const std::string body = gzip_bytes(std::string(8u << 20, 'A'));  // 8 MB unpacked, over the 1 MB limit
  RawSocket s(server_->port());
  s.send("POST /v1/jobs HTTP/1.1\r\nHost: t\r\nContent-Type: application/octet-stream\r\nContent-Encoding: gzip\r\n"
         "Content-Length: " + std::to_string(body.size() + smuggled.size()) + "\r\n\r\n");
  s.send(body + smuggled);
  bool closed = false;
  const std::string answer = s.read_until_closed(20s, &closed);
  EXPECT_TRUE(closed) << "the connection stayed open";
  EXPECT_EQ(answer.rfind("HTTP/1.1 413", 0), 0u) << answer.substr(0, 300);
  EXPECT_EQ(answer.find("HTTP/1.1", 1), std::string::npos) << "a second response: " << answer;
  expect_healthy();
}

// Finding 7: clients trickling heads hold no HTTP thread; the probes answer
// at once, and the trickling connections get 408 at the header deadline.
TEST_F(Hardening, SlowHeadsDoNotStarveTheProbes) {
  start({"--http-threads", "2", "--header-timeout", "2"});
  std::vector<std::unique_ptr<RawSocket>> slow;
  for (int i = 0; i < 40; ++i) {
    slow.push_back(std::make_unique<RawSocket>(server_->port()));
    slow.back()->send("GET /healthz HTTP/1.1\r\nHost: t\r\n");
  }
  for (int round = 0; round < 3; ++round) {
    const auto t0 = std::chrono::steady_clock::now();
    auto client = make_client(server_->port(), 2);
    auto health = client->Get("/healthz");
    ASSERT_TRUE(health) << "the probe got no answer while 40 heads trickle";
    EXPECT_EQ(health->status, 200);
    EXPECT_LT(std::chrono::steady_clock::now() - t0, 1s);
    for (auto& s : slow) s->send("X");  // still sending
    std::this_thread::sleep_for(400ms);
  }
  for (auto& s : slow) {
    bool closed = false;
    const std::string answer = s->read_until_closed(5s, &closed);
    EXPECT_TRUE(closed);
    EXPECT_EQ(answer.rfind("HTTP/1.1 408", 0), 0u) << answer;
  }
  expect_healthy();
}

// Finding 7: a body shorter than its Content-Length, or trickled, is dropped
// at its deadline (grace + size at the minimum rate), not held for ever.
TEST_F(Hardening, StalledBodiesAreDroppedAtTheirDeadline) {
  start({"--http-threads", "1", "--body-grace", "2", "--body-min-rate", "1000000", "--read-timeout", "60"});
  RawSocket s(server_->port());
  s.send("POST /v1/jobs HTTP/1.1\r\nHost: t\r\nContent-Type: application/octet-stream\r\nContent-Length: 1000000\r\n\r\n");
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < 40; ++i) {  // 1 byte every 100 ms: the read timeout alone would never end it
    if (!s.send("x")) break;
    std::this_thread::sleep_for(100ms);
  }
  bool closed = false;
  s.read_until_closed(10s, &closed);
  EXPECT_TRUE(closed);
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 8s);
  expect_healthy();  // the only HTTP thread is free again
}

// Finding 8: an OBJ index of INT64_MIN is refused, not read out of bounds.
TEST_F(Hardening, ObjIndexOfInt64MinIsAnInvalidMesh) {
  start();
  const std::string obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -9223372036854775808 1 2\n";
  const json p = expect_problem(post_raw(http(), "/v1/voxelize?filename=a.obj", bytes_of(obj), ""), 422, "invalid-mesh");
  EXPECT_NE(p.at("detail").get<std::string>().find("-9223372036854775808"), std::string::npos) << p.dump();
  expect_healthy();
}

// Finding 9: a burst far past the HTTP threads and the job queue gets 202s
// and 429s with Retry-After, never a reset connection.
TEST_F(Hardening, BurstsGet429NotResets) {
  start({"--workers", "1", "--queue-size", "4", "--http-threads", "4", "--http-queue", "16"});
  const std::vector<std::uint8_t> mesh = to_binary_stl(make_icosphere({0, 0, 0}, 1, 3));
  constexpr int kClients = 200;
  std::atomic<int> accepted{0}, busy{0}, other{0};
  std::vector<std::thread> clients;
  for (int i = 0; i < kClients; ++i)
    clients.emplace_back([&, i] {
      auto client = make_client(server_->port(), 60);
      auto res = post_multipart(*client, "/v1/jobs", mesh, "part.stl",
                                R"({"grid": {"resolution": )" + std::to_string(64 + i) + "}}");
      if (res && res->status == 202) ++accepted;
      else if (res && res->status == 429 && res->has_header("Retry-After")) ++busy;
      else ++other;
    });
  for (auto& t : clients) t.join();
  EXPECT_EQ(other.load(), 0) << "answers other than 202 or 429 (or no answer at all)";
  EXPECT_EQ(accepted + busy, kClients);
  EXPECT_GT(busy.load(), 0);
  EXPECT_GE(accepted.load(), 4);
  expect_healthy();
}

// Finding 10: a synchronous request whose client leaves stops its job; the
// only worker is free for the next job long before the abandoned one would
// have ended (about 20 s of CPU on this machine).
TEST_F(Hardening, AbandonedSyncRequestsCancelTheirJob) {
  start({"--workers", "1", "--sync-max-voxels", "100000000"});
  {
    auto impatient = make_client(server_->port(), 1);
    auto res = post_raw(*impatient, "/v1/voxelize?format=raw", to_binary_stl(make_icosphere({0, 0, 0}, 1, 4)),
                        R"({"mode": "sdf", "sdf": {"band": "full"}, "grid": {"resolution": 400}})");
    EXPECT_FALSE(res) << "the client was meant to give up first";
  }
  const auto t0 = std::chrono::steady_clock::now();
  const json job = submit(to_binary_stl(make_box({0, 0, 0}, {1, 2, 3})), R"({"grid": {"resolution": 16}})");
  finished(job);
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 10s);
  EXPECT_NE(server_->log().find("went away; cancelling"), std::string::npos) << server_->log();
}

// Finding 13: control characters from a request never reach the log.
TEST_F(Hardening, RequestFieldsCannotForgeLogLines) {
  start();
  const std::string forged = "abc\r\n2026-01-01T00:00:00.000Z info FORGED\x1b[31m";
  auto res = http().Get("/healthz", {{"X-Request-Id", forged}});
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 200);
  const std::string echoed = res->get_header_value("X-Request-Id");
  EXPECT_EQ(echoed.find_first_of("\r\n\x1b"), std::string::npos) << echoed;
  auto plain = http().Get("/healthz", {{"X-Request-Id", "trace-42.a:b"}});
  ASSERT_TRUE(plain);
  EXPECT_EQ(plain->get_header_value("X-Request-Id"), "trace-42.a:b");
  RawSocket s(server_->port());
  s.send("GET /v1/jobs/%0d%0a%1b[2Jx HTTP/1.1\r\nHost: t\r\nConnection: close\r\n\r\n");
  s.read_until_closed(5s);
  expect_healthy();
  const std::string log = server_->log();
  EXPECT_EQ(log.find('\x1b'), std::string::npos);
  EXPECT_EQ(log.find('\r'), std::string::npos);
  EXPECT_EQ(log.find("\nFORGED"), std::string::npos);
  EXPECT_EQ(log.find("info FORGED"), std::string::npos);
}

// Finding 14: a job running when the process is killed is reported as
// interrupted while running.
TEST_F(Hardening, AJobRunningAtAKillIsReportedAsRunning) {
  start({"--workers", "1"});
  const json job = submit(to_binary_stl(make_icosphere({0, 0, 0}, 1, 4)),
                          R"({"mode": "sdf", "sdf": {"band": "full"}, "grid": {"resolution": 400}})");
  const std::string id = job.at("id");
  wait_for_state(http(), id, "running", 30);
  server_->kill_hard();
  start({"--workers", "1"});
  const json status = expect_json(http().Get(("/v1/jobs/" + id).c_str()), 200, "JobStatus");
  EXPECT_EQ(status.at("state"), "failed");
  EXPECT_EQ(status.at("error").at("type"), "urn:voxd:problem:interrupted");
  EXPECT_NE(status.at("error").at("detail").get<std::string>().find("was running"), std::string::npos) << status.dump();
}

}  // namespace
}  // namespace voxd::test

namespace voxd::test {
namespace {

std::string varint(std::uint64_t v) {
  std::string out;
  do {
    const std::uint8_t b = v & 0x7f;
    v >>= 7;
    out += static_cast<char>(b | (v ? 0x80 : 0));
  } while (v);
  return out;
}

// A Draco 2.2 edgebreaker header claiming `faces` and `vertices`, then
// zeros: the shape of the fuzzer's 74-122 byte files.
std::string hostile_draco(std::uint64_t faces, std::uint64_t vertices) {
  std::string d = "DRACO";
  d += std::string("\x02\x02\x01\x01\x00\x00", 6);
  d += '\0' + varint(vertices) + varint(faces) + '\0' + varint(1) + varint(0);
  return d + std::string(60, '\0');
}

// Finding 1: Draco headers claiming billions of faces are refused before
// libdraco sizes a buffer from them; one that passes the checks is decoded
// in a child process whose memory is limited.
TEST_F(Hardening, HostileDracoHeadersAreRefusedWithBoundedMemory) {
  start();
  const std::uint64_t before = warm_peak();
  const json over = expect_problem(
      post_raw(http(), "/v1/jobs?filename=a.drc", bytes_of(hostile_draco(1'130'000'000, 500'000'000)), ""), 422,
      "limit-exceeded");
  EXPECT_NE(over.at("detail").get<std::string>().find("1130000000"), std::string::npos) << over.dump();
  const json dense = expect_problem(
      post_raw(http(), "/v1/jobs?filename=a.drc", bytes_of(hostile_draco(5'000'000, 2'500'000)), ""), 422,
      "invalid-mesh");
  EXPECT_NE(dense.at("detail").get<std::string>().find("bytes can encode"), std::string::npos) << dense.dump();
  expect_problem(post_raw(http(), "/v1/jobs?filename=a.drc", bytes_of(hostile_draco(60'000, 50'000)), ""), 422,
                 "invalid-mesh");
  expect_peak_growth_below(before, std::uint64_t{64} << 20);
  expect_healthy();
}

TEST_F(Hardening, DracoPastTheDecoderMemoryLimitIsA422) {
  ASSERT_TRUE(draco_encoder_available()) << "scripts/install-deps.sh installs Debian's draco";
  start({"--max-decode-memory", std::to_string(16u << 20)});
  const std::vector<std::uint8_t> big = encode_with_draco_encoder(make_icosphere({0, 0, 0}, 1, 7), "");
  const json p = expect_problem(post_raw(http(), "/v1/jobs?filename=a.drc", big, ""), 422, "invalid-mesh");
  EXPECT_NE(p.at("detail").get<std::string>().find("max-decode-memory"), std::string::npos) << p.dump();
  // The same file decodes with the default limit, to the same mesh as in process.
  server_->stop();
  start();
  const json job = submit(big, R"({"grid": {"resolution": 32}})", "a.drc");
  finished(job);
  EXPECT_EQ(volume(job.at("id"), "?format=rle"), cli_volume(big, "a.drc", R"({"grid": {"resolution": 32}})"));
}

}  // namespace
}  // namespace voxd::test

namespace voxd::test {
namespace {

// Finding 4: a queued job's decoded mesh is held against the memory budget
// from its acceptance, so uploads behind a busy worker are refused with 429
// once the budget is taken, instead of piling up until the process dies.
// Issue #39: fixing glibc's mmap threshold (above) also fixed its trim
// threshold at 128 KiB, so after every small job each thread's arena gave
// its free memory back and faulted it in again for the next: 330 page
// faults a 10,000-triangle job. The server keeps up to 8 MiB an arena now;
// the page faults of a run of small jobs after the first few are counted
// from /proc (minor faults, field 10 of its stat): 24 a job now.
TEST_F(Hardening, SmallJobsReuseTheirMemoryInsteadOfFaultingItInAgain) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer replaces glibc's malloc, whose arenas this test measures";
#endif
  start();
  // The service benchmark's small job (bench/http_bench.sh).
  const std::vector<std::uint8_t> mesh = to_binary_stl(make_torus({0, 0, 0}, 40, 10, 100, 50));
  auto sync_job = [&] {
    auto res = post_multipart(http(), "/v1/voxelize", mesh, "part.stl", R"({"grid":{"resolution":64}})");
    ASSERT_TRUE(res);
    ASSERT_EQ(res->status, 200) << res->body;
  };
  auto minor_faults = [&] {
    std::ifstream stat("/proc/" + std::to_string(server_->pid()) + "/stat");
    std::string text((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
    std::istringstream fields(text.substr(text.rfind(')') + 2));  // after the command name
    std::string field;
    for (int f = 3; f <= 10; ++f) fields >> field;  // state is field 3, minflt field 10
    return std::stoull(field);
  };
  for (int i = 0; i < 10; ++i) sync_job();
  const std::uint64_t before = minor_faults();
  constexpr int kJobs = 40;
  for (int i = 0; i < kJobs; ++i) sync_job();
  const std::uint64_t per_job = (minor_faults() - before) / kJobs;
  EXPECT_LT(per_job, 100u) << "page faults a small job (about 350 before)";
}

TEST_F(Hardening, QueuedMeshesAreAdmittedWithinTheMemoryBudget) {
  constexpr std::uint64_t kBudget = std::uint64_t{400} << 20;
  start({"--workers", "1", "--memory-budget", std::to_string(kBudget)});
  const std::uint64_t before = warm_peak();
  const json blocker = submit(to_binary_stl(make_icosphere({0, 0, 0}, 1, 4)),
                              R"({"mode": "sdf", "sdf": {"band": "full"}, "grid": {"resolution": 300}})");
  const std::string blocker_id = blocker.at("id");
  wait_for_state(http(), blocker_id, "running", 30);
  Mesh many = make_box({0, 0, 0}, {1, 1, 1});
  many.vertices.resize(4'000'000, glm::vec3(0.5f));  // 48 MB of vertices for 12 triangles
  PlyOptions binary;
  binary.encoding = PlyOptions::Encoding::binary_little_endian;
  const std::vector<std::uint8_t> ply = to_ply(many, binary);
  int accepted = 0, busy = 0;
  for (int i = 0; i < 20; ++i) {
    auto res = post_raw(http(), "/v1/jobs?filename=part.ply", ply, R"({"grid": {"resolution": )" + std::to_string(16 + i) + "}}");
    ASSERT_TRUE(res);
    if (res->status == 202) {
      ++accepted;
      continue;
    }
    const json p = expect_problem(res, 429, "memory-busy");
    EXPECT_TRUE(res->has_header("Retry-After"));
    EXPECT_NE(p.at("detail").get<std::string>().find("MiB"), std::string::npos) << p.dump();
    ++busy;
  }
  EXPECT_GE(accepted, 1);
  EXPECT_GE(busy, 10);
  expect_peak_growth_below(before, kBudget + (std::uint64_t{160} << 20));
  ASSERT_TRUE(http().Delete(("/v1/jobs/" + blocker_id).c_str()));
  wait_for_job(http(), blocker_id);
  expect_healthy();
}

// Finding 5: an analysis whose estimate could never fit is refused up front
// (it used to kill the server with several full float copies); one that fits
// is answered.
TEST_F(Hardening, AnalysesAreAdmittedWithinTheMemoryBudget) {
  start({"--memory-budget", std::to_string(256u << 20)});
  const std::uint64_t before = warm_peak();
  const std::string id = finished(submit(to_binary_stl(make_icosphere({0, 0, 0}, 1, 4)), R"({"grid": {"resolution": 256}})"));
  const json p = expect_problem(http().Get(("/v1/jobs/" + id + "/thickness?format=raw").c_str()), 422, "limit-exceeded");
  EXPECT_NE(p.at("detail").get<std::string>().find("--memory-budget"), std::string::npos) << p.dump();
  auto radiograph = http().Get(("/v1/jobs/" + id + "/radiography?axis=z&format=json").c_str());
  ASSERT_TRUE(radiograph);
  EXPECT_EQ(radiograph->status, 200) << radiograph->body;
  expect_peak_growth_below(before, std::uint64_t{256} << 20);
  expect_healthy();
}

}  // namespace
}  // namespace voxd::test

namespace voxd::test {
namespace {

// `voxd serve` in a mount namespace of its own whose data directory is a
// tmpfs of `megabytes`, with `filler_kb` of it taken by a file.
std::vector<std::string> on_small_disk(const std::string& data_dir, int megabytes, int filler_kb) {
  std::filesystem::create_directories(data_dir);
  const std::string script = "mount -t tmpfs -o size=" + std::to_string(megabytes) + "m tmpfs " + data_dir +
                             " && dd if=/dev/zero of=" + data_dir + "/filler bs=1k count=" + std::to_string(filler_kb) +
                             " 2>/dev/null && exec \"$@\"";
  return {"/usr/bin/unshare", "-m", "--", "/bin/sh", "-c", script, "voxd-on-small-disk"};
}

// Finding 11: a result that does not fit fails its job with storage-full and
// leaves nothing behind (the next small job still fits); below the free-space
// floor, submissions get 507 and /readyz is not ready.
TEST_F(Hardening, AFullDiskFailsJobsCleanlyAndMakesTheServiceNotReady) {
  start({"--min-free-disk", "65536"}, {}, on_small_disk(dir_ + "/data", 4, 3000));
  // A full distance field: 4 MB of floats, more than the disk has free.
  const json big = submit(to_binary_stl(make_icosphere({0, 0, 0}, 1, 3)),
                          R"({"mode": "sdf", "sdf": {"band": "full"}, "grid": {"resolution": 100}})");
  const json failed = wait_for_job(http(), big.at("id"));
  EXPECT_EQ(failed.at("state"), "failed") << failed.dump();
  EXPECT_EQ(failed.at("error").at("type"), "urn:voxd:problem:storage-full") << failed.dump();
  EXPECT_EQ(failed.at("error").at("status"), 507);
  auto ready = http().Get("/readyz");
  ASSERT_TRUE(ready);
  EXPECT_EQ(ready->status, 200) << "the failed write must not keep the disk full: " << ready->body;
  expect_healthy();
  server_->stop();

  start({"--min-free-disk", std::to_string(2u << 20)}, {}, on_small_disk(dir_ + "/data", 4, 3000));
  auto not_ready = http().Get("/readyz");
  ASSERT_TRUE(not_ready);
  EXPECT_EQ(not_ready->status, 503);
  EXPECT_NE(not_ready->body.find("disk"), std::string::npos) << not_ready->body;
  const json p = expect_problem(post_multipart(http(), "/v1/jobs", to_binary_stl(make_box({0, 0, 0}, {1, 1, 1})),
                                               "part.stl", "{}"),
                                507, "storage-full");
  EXPECT_NE(p.at("detail").get<std::string>().find("MiB free"), std::string::npos) << p.dump();
  auto health = http().Get("/healthz");
  ASSERT_TRUE(health);
  EXPECT_EQ(health->status, 200);
}

}  // namespace
}  // namespace voxd::test
