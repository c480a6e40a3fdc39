// The HTTP edge against raw requests to a real `voxd serve` (issue #37's
// findings 1 to 4 and the scheme of 9): nothing after a refused
// body is parsed as a request, event streams never take an HTTP thread
// whatever the request line looks like, a burst of streams all start at
// once, and a port in use is an error, not a shared port.
#include <atomic>
#include <chrono>
#include <cstdio>
#include <memory>
#include <regex>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "support/http_fixture.h"
#include "support/raw_socket.h"

namespace voxd::test {
namespace {

using namespace std::chrono_literals;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

// How many HTTP responses a byte stream holds (its status lines).
int count_responses(const std::string& bytes) {
  static const std::regex status_line("HTTP/1\\.1 [1-5][0-9][0-9] ");
  return static_cast<int>(std::distance(std::sregex_iterator(bytes.begin(), bytes.end(), status_line), std::sregex_iterator()));
}

class HttpEdge : public HttpServiceTest {
 protected:
  // A hollow box at a fine grid with its wall thickness: a job of seconds.
  std::string slow_job() {
    const auto mesh = to_binary_stl(concat({make_box({0, 0, 0}, {20, 16, 12}), flipped(make_box({2, 2, 2}, {18, 14, 10}))}));
    return submit(mesh, R"({"grid": {"resolution": 360}, "analyses": [{"kind": "analysis", "min_wall": 1}]})").at("id");
  }
  // With one worker: a slow job running and a second queued behind it, whose
  // event streams stay open for as long as both take. Returns the second.
  std::string queued_job() {
    slow_job();
    return slow_job();
  }
  bool job_finished(const std::string& id) {
    auto res = http().Get(("/v1/jobs/" + id).c_str());
    return res && res->status == 200 && finished_state(json::parse(res->body).at("state"));
  }
  static bool finished_state(const std::string& s) { return s == "succeeded" || s == "failed" || s == "cancelled"; }
};

// Finding 1: a request with a body refused before it was read (401 without
// a key; a CORS preflight answered 204) closes its connection: a request
// inside that body is never answered.
TEST_F(HttpEdge, NothingAfterARefusedBodyIsParsedAsARequest) {
  start({"--api-keys", "k1", "--cors-origins", "https://app.example"});
  const std::string smuggled = "GET /healthz HTTP/1.1\r\nHost: t\r\n\r\n";
  const std::string chunked_smuggle = "5\r\nhello\r\n0\r\n\r\n" + smuggled;
  struct Case {
    std::string name, head, body, expect;
  };
  std::vector<Case> cases = {
      {"401 with a Content-Length body",
       "POST /v1/jobs HTTP/1.1\r\nHost: t\r\nContent-Type: application/octet-stream\r\nContent-Length: " +
           std::to_string(smuggled.size()) + "\r\n\r\n",
       smuggled, "HTTP/1.1 401"},
      {"401 with a chunked body",
       "POST /v1/jobs HTTP/1.1\r\nHost: t\r\nContent-Type: application/octet-stream\r\nTransfer-Encoding: chunked\r\n\r\n",
       chunked_smuggle, "HTTP/1.1 401"},
      {"401 on a GET with a body",
       "GET /v1/jobs HTTP/1.1\r\nHost: t\r\nContent-Length: " + std::to_string(smuggled.size()) + "\r\n\r\n", smuggled,
       "HTTP/1.1 401"},
      {"preflight with a body",
       "OPTIONS /v1/jobs HTTP/1.1\r\nHost: t\r\nOrigin: https://app.example\r\nAccess-Control-Request-Method: POST\r\n"
       "Content-Length: " + std::to_string(smuggled.size()) + "\r\n\r\n",
       smuggled, "HTTP/1.1 204"},
      // Refused before httplib sees it: it reads only "chunked".
      {"a transfer coding httplib does not read",
       "POST /v1/jobs HTTP/1.1\r\nHost: t\r\nTransfer-Encoding: gzip, chunked\r\n\r\n", chunked_smuggle, "HTTP/1.1 400"},
  };
  // Two readers could frame these two ways (RFC 9112 6.3): refused, closed.
  cases.push_back({"two Content-Lengths",
                   "POST /v1/jobs HTTP/1.1\r\nHost: t\r\nAuthorization: Bearer k1\r\nContent-Length: 0\r\nContent-Length: " +
                       std::to_string(smuggled.size()) + "\r\n\r\n",
                   smuggled, "HTTP/1.1 400"});
  cases.push_back({"Content-Length with Transfer-Encoding",
                   "POST /v1/jobs HTTP/1.1\r\nHost: t\r\nAuthorization: Bearer k1\r\nContent-Length: 3\r\n"
                   "Transfer-Encoding: chunked\r\n\r\n",
                   chunked_smuggle, "HTTP/1.1 400"});
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    RawSocket s(server_->port());
    s.send(c.head + c.body);
    bool closed = false;
    const std::string answer = s.read_until_closed(10s, &closed);
    EXPECT_EQ(answer.rfind(c.expect, 0), 0u) << answer.substr(0, 300);
    EXPECT_EQ(count_responses(answer), 1) << "a request was parsed out of the refused body:\n" << answer;
    EXPECT_TRUE(closed) << "the connection stayed open after a refused body";
  }
  // A request with no body keeps its connection: a second one is answered.
  RawSocket s(server_->port());
  s.send("GET /v1/jobs HTTP/1.1\r\nHost: t\r\nAuthorization: Bearer k1\r\n\r\n" + smuggled);
  std::string answer;
  for (const auto until = Clock::now() + 10s; answer.find("\"status\":\"ok\"") == std::string::npos && Clock::now() < until;)
    answer += s.read_some(1s);
  EXPECT_EQ(count_responses(answer), 2) << answer;
  EXPECT_NE(answer.find("\"status\":\"ok\""), std::string::npos) << answer;
}

// A broken head that httplib answers itself (400) closes the connection
// too: what followed it is not a request.
TEST_F(HttpEdge, NothingAfterABrokenHeadIsParsedAsARequest) {
  start();
  RawSocket s(server_->port());
  s.send("POST /v1/jobs HTTP/1.1 extra\r\nHost: t\r\nContent-Length: 34\r\n\r\n"
         "GET /healthz HTTP/1.1\r\nHost: t\r\n\r\n");
  bool closed = false;
  const std::string answer = s.read_until_closed(10s, &closed);
  EXPECT_EQ(answer.rfind("HTTP/1.1 400", 0), 0u) << answer.substr(0, 300);
  EXPECT_EQ(count_responses(answer), 1) << answer;
  EXPECT_TRUE(closed);
}

// Finding 9: the scheme of Authorization is case-insensitive.
TEST_F(HttpEdge, TheBearerSchemeIsCaseInsensitive) {
  start({"--api-keys", "k1"});
  for (const std::string scheme : {"Bearer", "bearer", "BEARER"}) {
    auto res = http().Get("/v1/jobs", {{"Authorization", scheme + " k1"}});
    ASSERT_TRUE(res);
    EXPECT_EQ(res->status, 200) << scheme << ": " << res->body;
  }
  for (const std::string wrong : {"Bearer k2", "Basic k1", "Bearerk1", "bearer "}) {
    auto res = http().Get("/v1/jobs", {{"Authorization", wrong}});
    ASSERT_TRUE(res);
    expect_problem(res, 401, "unauthorized");
  }
}

// The job id with its first character percent-encoded, as httplib decodes it.
std::string encoded_events_path(const std::string& id) {
  char escaped[4];
  std::snprintf(escaped, sizeof escaped, "%%%02X", static_cast<unsigned char>(id[0]));
  return "/v1/jobs/" + std::string(escaped) + id.substr(1) + "/events";
}

// Opens a raw event stream; returns once its first bytes came (or 10 s).
std::unique_ptr<RawSocket> open_stream(int port, const std::string& request, std::string* first = nullptr) {
  auto s = std::make_unique<RawSocket>(port);
  s->send(request);
  const std::string got = s->read_some(10s);
  if (first) *first = got;
  return s;
}

// Finding 2: event streams whose path is percent-encoded, or that are
// pipelined behind another request, run on stream threads and count toward
// --max-event-streams: with two HTTP threads, /healthz still answers at once.
TEST_F(HttpEdge, EventStreamsInAnySpellingLeaveTheHttpThreadsFree) {
  start({"--http-threads", "2", "--workers", "1", "--max-event-streams", "3"});
  const std::string id = queued_job();
  std::vector<std::unique_ptr<RawSocket>> streams;
  std::string first;
  streams.push_back(open_stream(server_->port(), "GET " + encoded_events_path(id) + " HTTP/1.1\r\nHost: t\r\n\r\n", &first));
  EXPECT_EQ(first.rfind("HTTP/1.1 200", 0), 0u) << first;
  streams.push_back(open_stream(server_->port(), "GET /v1/jobs/" + id + "/event%73?x=1 HTTP/1.1\r\nHost: t\r\n\r\n", &first));
  EXPECT_EQ(first.rfind("HTTP/1.1 200", 0), 0u) << first;
  // A line that is not strict HTTP/1.1 (httplib would read runs of spaces as
  // one) is refused before any thread takes it.
  // Nor a target that is not a path (httplib routes "?/v1/..." as "/v1/..."),
  // nor one with a fragment (httplib drops "#..." before routing).
  for (const auto& [line, why] : std::vector<std::pair<std::string, std::string>>{
           {"GET  /v1/jobs/" + id + "/events  HTTP/1.1", "the request line is not METHOD SP TARGET SP HTTP/1.1"},
           {"GET ?/v1/jobs/" + id + "/events HTTP/1.1", "the request target is not a path starting with /"},
           {"GET /v1/jobs/" + id + "/events#x HTTP/1.1", "the request target holds a fragment ('#')"}}) {
    RawSocket odd(server_->port());
    odd.send(line + "\r\nHost: t\r\n\r\n");
    const std::string refused = odd.read_until_closed(5s);
    EXPECT_EQ(refused.rfind("HTTP/1.1 400", 0), 0u) << line << ": " << refused;
    EXPECT_NE(refused.find(why), std::string::npos) << line << ": " << refused;
  }
  // Pipelined behind a plain request: both answers come, the stream stays.
  streams.push_back(open_stream(server_->port(),
                                "GET /healthz HTTP/1.1\r\nHost: t\r\n\r\nGET /v1/jobs/" + id + "/events HTTP/1.1\r\nHost: t\r\n\r\n",
                                &first));
  for (const auto until = Clock::now() + 10s; count_responses(first) < 2 && Clock::now() < until;)
    first += streams.back()->read_some(1s);
  EXPECT_EQ(count_responses(first), 2) << first;
  ASSERT_FALSE(job_finished(id)) << "the job ended before the streams were all open: make it slower";

  // Every HTTP thread is free: probes answer at once, many times over.
  auto quick = make_client(server_->port(), 2);
  for (int i = 0; i < 10; ++i) {
    const auto t0 = Clock::now();
    auto health = quick->Get("/healthz");
    ASSERT_TRUE(health) << "/healthz not answered while three streams are open";
    EXPECT_EQ(health->status, 200);
    EXPECT_LT(Clock::now() - t0, 1s);
  }
  // All three count: a fourth, in any spelling, is refused at once.
  auto metrics = quick->Get("/metrics");
  ASSERT_TRUE(metrics);
  EXPECT_NE(metrics->body.find("voxd_event_streams_open 3\n"), std::string::npos) << metrics->body;
  RawSocket fourth(server_->port());
  fourth.send("GET " + encoded_events_path(id) + " HTTP/1.1\r\nHost: t\r\n\r\n");
  const std::string refused = fourth.read_until_closed(5s);
  EXPECT_EQ(refused.rfind("HTTP/1.1 503", 0), 0u) << refused.substr(0, 300);
  EXPECT_NE(refused.find("too-many-streams"), std::string::npos) << refused;
  ASSERT_FALSE(job_finished(id)) << "the job ended during the checks: make it slower";
}

// Finding 3: a burst of streams on a queued job all get their first event
// at once, each on a stream thread of its own.
TEST_F(HttpEdge, ABurstOfStreamsAllStartAtOnce) {
  start({"--workers", "1", "--max-event-streams", "64"});
  // Streams that ended leave their threads idle, as on a server that has
  // run a while: 20 of them, on a job that then ends.
  const std::string first = slow_job();
  const std::string id = queued_job();  // behind `first` and one more
  {
    std::vector<std::unique_ptr<RawSocket>> earlier;
    for (int i = 0; i < 20; ++i)
      earlier.push_back(open_stream(server_->port(), "GET /v1/jobs/" + first + "/events HTTP/1.1\r\nHost: t\r\nConnection: close\r\n\r\n"));
    wait_for_job(http(), first, 600);  // however slow the build (a sanitizer's is)
    for (auto& s : earlier) EXPECT_NE(s->read_until_closed(30s).find("event: end"), std::string::npos);
  }
  ASSERT_FALSE(job_finished(id)) << "the queued job ended too soon: make the jobs slower";
  constexpr int kStreams = 40;
  std::vector<std::unique_ptr<RawSocket>> streams;
  for (int i = 0; i < kStreams; ++i) streams.push_back(std::make_unique<RawSocket>(server_->port()));
  std::this_thread::sleep_for(200ms);  // all connected, then all their heads at once
  for (auto& s : streams) s->send("GET /v1/jobs/" + id + "/events HTTP/1.1\r\nHost: t\r\n\r\n");
  const auto deadline = Clock::now() + 3s;
  int started = 0;
  for (auto& s : streams) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
    std::string got = s->read_some(std::max(left, 1ms));
    for (; got.find("event: job") == std::string::npos && Clock::now() < deadline;) {
      const std::string more = s->read_some(std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()) + 1ms);
      if (more.empty()) break;
      got += more;
    }
    if (got.find("event: job") != std::string::npos && got.find("\"state\":\"queued\"") != std::string::npos) ++started;
  }
  EXPECT_EQ(started, kStreams) << "streams with their first event (the job, queued) within 3 s";
  ASSERT_FALSE(job_finished(id)) << "the job ended within the 3 s: make it slower";
}

// Finding 4: a second server on a port in use fails to start, saying so,
// instead of sharing the port and half its connections.
TEST_F(HttpEdge, ASecondServerOnAPortInUseFailsToStart) {
  start();
  const std::string other = make_temp_dir("voxd-second");
  const auto r = run_process("timeout 20 " + serve_binary() + " serve --host 127.0.0.1 --port " +
                             std::to_string(server_->port()) + " --data-dir " + other + "/data");
  EXPECT_NE(r.exit_code, 124) << "the second server started and served the same port:\n" << r.err;
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("port is in use"), std::string::npos) << r.err;
  // The first still answers every connection.
  for (int i = 0; i < 8; ++i) {
    auto client = make_client(server_->port(), 5);
    auto res = client->Get("/healthz");
    ASSERT_TRUE(res);
    EXPECT_EQ(res->status, 200);
  }
  std::filesystem::remove_all(other);
}

// Multipart bodies are read by the service's own reader (httplib's copied
// them a byte at a time): a mesh whose bytes hold the boundary's start, in
// a body with a quoted boundary, a preamble and the parts in another order,
// voxelizes to the same bytes as the raw upload of the same mesh; a body
// with no boundary, or none that closes it, is a 400 that says so.
TEST_F(HttpEdge, AMultipartBodyIsReadAsSentWhateverItsBytesLookLike) {
  start();
  const std::string boundary = "voxd boundary";
  std::vector<std::uint8_t> mesh = to_binary_stl(make_box({0, 0, 0}, {3, 2, 1}));
  // In the STL's header: the delimiter less its last byte, and the boundary
  // with no CRLF right before it.
  const std::string header = "\r\n--voxd boundar\r\n---voxd boundary\r\n";
  std::copy(header.begin(), header.end(), mesh.begin());
  const std::string params = R"({"grid": {"resolution": 32}})";
  const std::string body = "a preamble\r\n--" + boundary + "\r\nContent-Disposition: form-data; name=\"params\"\r\n\r\n" +
                           params + "\r\n--" + boundary +
                           "\r\nContent-Disposition: form-data; name=\"mesh\"; filename=\"box.stl\"\r\n"
                           "Content-Type: application/octet-stream\r\n\r\n" +
                           std::string(mesh.begin(), mesh.end()) + "\r\n--" + boundary + "--\r\n";
  auto multipart = http().Post("/v1/voxelize", body, "multipart/form-data; boundary=\"" + boundary + "\"");
  ASSERT_TRUE(multipart);
  ASSERT_EQ(multipart->status, 200) << multipart->body.substr(0, 500);
  auto raw = post_raw(http(), "/v1/voxelize", mesh, params, "application/octet-stream");
  ASSERT_TRUE(raw);
  ASSERT_EQ(raw->status, 200) << raw->body.substr(0, 500);
  EXPECT_EQ(multipart->body, raw->body);
  EXPECT_GT(multipart->body.size(), 100u);

  const json no_boundary = expect_problem(http().Post("/v1/voxelize", body, "multipart/form-data"), 400, "bad-request");
  EXPECT_NE(no_boundary.at("detail").get<std::string>().find("no boundary parameter"), std::string::npos) << no_boundary;
  const std::string unclosed = body.substr(0, body.rfind("\r\n--"));
  const json truncated =
      expect_problem(http().Post("/v1/voxelize", unclosed, "multipart/form-data; boundary=\"" + boundary + "\""), 400,
                     "bad-request");
  EXPECT_NE(truncated.at("detail").get<std::string>().find("malformed multipart"), std::string::npos) << truncated;
  auto healthy = make_client(server_->port(), 5)->Get("/healthz");
  ASSERT_TRUE(healthy);
  EXPECT_EQ(healthy->status, 200);
}

}  // namespace
}  // namespace voxd::test
