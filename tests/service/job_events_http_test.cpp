// GET /v1/jobs/{id}/events against a real `voxd serve`: the events of a job
// in order, a late subscriber, a cancelled job, several subscribers at once,
// and open streams that leave the HTTP threads to everyone else.
#include <atomic>
#include <thread>

#include "support/http_fixture.h"
#include "support/redis_process.h"

namespace voxd::test {
namespace {

using nlohmann::json;

struct Event {
  long long id = 0;
  std::string name;
  json data;
};

// Reads a job's stream to its end (or until `stop` says so), as a client's
// EventSource would.
std::vector<Event> read_events(int port, const std::string& id, int* status = nullptr,
                               const std::function<bool(const Event&)>& on_event = {}) {
  auto client = make_client(port, 120);
  std::vector<Event> events;
  std::string buffer;
  auto res = client->Get(("/v1/jobs/" + id + "/events").c_str(), [&](const char* data, std::size_t n) {
    buffer.append(data, n);
    for (std::size_t cut; (cut = buffer.find("\n\n")) != std::string::npos;) {
      const std::string block = buffer.substr(0, cut);
      buffer.erase(0, cut + 2);
      Event e;
      std::istringstream lines(block);
      for (std::string line; std::getline(lines, line);) {
        if (line.rfind("id: ", 0) == 0) e.id = std::stoll(line.substr(4));
        if (line.rfind("event: ", 0) == 0) e.name = line.substr(7);
        if (line.rfind("data: ", 0) == 0) e.data = json::parse(line.substr(6));
      }
      if (e.name.empty()) continue;  // retry: and keep-alive comments
      events.push_back(e);
      if (on_event && !on_event(e)) return false;
    }
    return true;
  });
  if (status) *status = res ? res->status : 0;
  return events;
}

std::vector<std::string> names(const std::vector<Event>& events) {
  std::vector<std::string> out;
  for (const auto& e : events) out.push_back(e.name);
  return out;
}

class JobEventsTest : public HttpServiceTest {
 protected:
  // A hollow box 20 x 16 x 12, walls 2 thick.
  std::vector<std::uint8_t> hollow_box() {
    return to_binary_stl(concat({make_box({0, 0, 0}, {20, 16, 12}), flipped(make_box({2, 2, 2}, {18, 14, 10}))}));
  }
  // A job that runs a few seconds: a fine grid and its wall thickness.
  std::string slow_job() {
    return submit(hollow_box(),
                  R"({"grid": {"resolution": 360}, "analyses": [{"kind": "analysis", "min_wall": 1}, {"kind": "radiography", "axis": "x"}]})")
        .at("id");
  }
};

// The stream is consistent with itself and with the job's final status.
void expect_well_formed(const std::vector<Event>& events, const json& final_status) {
  ASSERT_GE(events.size(), 2u);
  EXPECT_EQ(events.front().name, "job");
  EXPECT_EQ(events.back().name, "end");
  EXPECT_EQ(events.back().data, final_status);
  double progress = 0.0;
  std::vector<std::string> states;
  for (std::size_t i = 0; i < events.size(); ++i) {
    const Event& e = events[i];
    EXPECT_EQ(e.id, static_cast<long long>(i + 1)) << "event ids count up from 1";
    if (e.name == "job" || e.name == "state" || e.name == "progress" || e.name == "end") {
      const double p = e.data.at("progress");
      if (e.name != "end") {
        EXPECT_GE(p, progress) << "progress went back at event " << e.id;
        progress = p;
      }
    }
    if (e.name == "job" || e.name == "state" || e.name == "end") states.push_back(e.data.at("state"));
    if (e.name == "progress" || (e.name == "state" && e.data.at("state") == "running")) {
      EXPECT_TRUE(e.data.at("stage").is_string() || e.data.at("stage").is_null());
    }
  }
  // The states in the order a job moves through them, each once.
  const std::vector<std::string> order = {"queued", "running", final_status.at("state")};
  std::size_t at = 0;
  for (const std::string& s : states) {
    while (at < order.size() && order[at] != s) ++at;
    EXPECT_LT(at, order.size()) << "state " << s << " out of order";
  }
}

TEST_F(JobEventsTest, AJobsEventsComeInOrderWithEachAnalysisAsItIsReadyAndEndTheStream) {
  start();
  const std::string id = slow_job();
  const std::vector<Event> events = read_events(server_->port(), id);
  const json done = expect_json(http().Get(("/v1/jobs/" + id).c_str()), 200, "JobStatus");
  ASSERT_EQ(done.at("state"), "succeeded");
  expect_well_formed(events, done);
  ASSERT_NE(events.front().data.at("state"), "succeeded") << "the job ended before the stream began: make it slower";
  // Stages named while it ran, the voxelization's before the analyses'.
  std::vector<std::string> stages;
  for (const auto& e : events)
    if (e.name == "progress" && e.data.at("stage").is_string()) stages.push_back(e.data.at("stage"));
  ASSERT_FALSE(stages.empty());
  EXPECT_NE(std::find(stages.begin(), stages.end(), "analysis: analysis"), stages.end()) << json(stages).dump();
  // Each analysis once, as ready, before the end, with its entry's URL.
  std::vector<std::size_t> ready;
  for (const auto& e : events)
    if (e.name == "analysis") {
      EXPECT_EQ(e.data.at("state"), "ready");
      const std::size_t i = e.data.at("index");
      EXPECT_EQ(e.data.at("url"), done.at("analyses").at(i).at("url"));
      ready.push_back(i);
    }
  EXPECT_EQ(ready, (std::vector<std::size_t>{0, 1}));
}

TEST_F(JobEventsTest, AnAnalysisIsServedAsSoonAsItsEventSaysReady) {
  start();
  const std::string id = slow_job();
  std::string served;
  read_events(server_->port(), id, nullptr, [&](const Event& e) {
    if (e.name != "analysis" || e.data.at("index") != 0) return true;
    auto res = make_client(server_->port())->Get(e.data.at("url").get<std::string>().c_str());
    EXPECT_TRUE(res && res->status == 200) << (res ? res->body : "no answer");
    if (res) served = res->body;
    return true;
  });
  const json report = json::parse(served);
  EXPECT_NEAR(report.at("mass_properties").at("voxels").at("volume").get<double>(), 2304.0, 2304.0 * 0.02);
}

TEST_F(JobEventsTest, ALateSubscriberGetsTheJobAsItEndedAndTheEnd) {
  start();
  const json job = submit(hollow_box(), R"({"grid": {"resolution": 32}})");
  const std::string id = finished(job);
  const std::vector<Event> events = read_events(server_->port(), id);
  EXPECT_EQ(names(events), (std::vector<std::string>{"job", "end"}));
  const json done = expect_json(http().Get(("/v1/jobs/" + id).c_str()), 200, "JobStatus");
  EXPECT_EQ(events.at(0).data, done);
  EXPECT_EQ(events.at(1).data, done);
  // An EventSource reconnecting after the end is told to stop.
  auto again = http().Get(("/v1/jobs/" + id + "/events").c_str(), {{"Last-Event-ID", "2"}});
  ASSERT_TRUE(again);
  EXPECT_EQ(again->status, 204);
  EXPECT_TRUE(again->body.empty());
}

TEST_F(JobEventsTest, ACancelledJobsStreamEndsCancelled) {
  start();
  const std::string id = slow_job();
  std::atomic<bool> cancelled{false};
  const std::vector<Event> events = read_events(server_->port(), id, nullptr, [&](const Event& e) {
    const bool running = (e.name == "state" && e.data.at("state") == "running") || e.name == "progress" ||
                         (e.name == "job" && e.data.at("state") == "running");
    if (running && !cancelled.exchange(true)) {
      auto res = make_client(server_->port())->Delete(("/v1/jobs/" + id).c_str());
      EXPECT_TRUE(res && res->status == 202) << (res ? res->body : "no answer");
    }
    return true;
  });
  ASSERT_TRUE(cancelled);
  const json done = expect_json(http().Get(("/v1/jobs/" + id).c_str()), 200, "JobStatus");
  EXPECT_EQ(done.at("state"), "cancelled");
  expect_well_formed(events, done);
}

TEST_F(JobEventsTest, SeveralSubscribersAtOnceAllGetTheSameEnd) {
  start();
  const std::string id = slow_job();
  std::vector<std::vector<Event>> seen(4);
  std::vector<std::thread> readers;
  for (auto& s : seen) readers.emplace_back([&, port = server_->port()] { s = read_events(port, id); });
  for (auto& t : readers) t.join();
  const json done = expect_json(http().Get(("/v1/jobs/" + id).c_str()), 200, "JobStatus");
  for (const auto& events : seen) {
    expect_well_formed(events, done);
    std::size_t analyses = 0;
    for (const auto& e : events) analyses += e.name == "analysis";
    EXPECT_EQ(analyses, 2u);
  }
}

TEST_F(JobEventsTest, AnUnknownJobHasNoStream) {
  start();
  expect_problem(http().Get("/v1/jobs/0123456789abcdef0123456789abcdef/events"), 404, "not-found");
}

// Streams run on threads of their own: with 2 HTTP threads and 6 streams
// open, every other request is still answered, a 7th stream is refused with
// a 503 at once, and the streams still end with the job.
TEST_F(JobEventsTest, OpenStreamsDoNotStarveTheHttpThreads) {
  start({"--http-threads", "2", "--max-event-streams", "6"});
  const std::string id = slow_job();
  std::atomic<int> open{0};
  std::vector<std::vector<Event>> seen(6);
  std::vector<std::thread> readers;
  for (auto& s : seen)
    readers.emplace_back([&, port = server_->port()] {
      s = read_events(port, id, nullptr, [&](const Event& e) {
        if (e.name == "job") ++open;
        return true;
      });
    });
  for (int i = 0; i < 200 && open < 6; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  ASSERT_EQ(open, 6);
  // A short client timeout: a request queued behind the streams would miss it.
  auto quick = make_client(server_->port(), 5);
  for (int i = 0; i < 20; ++i) {
    auto res = quick->Get(("/v1/jobs/" + id).c_str());
    ASSERT_TRUE(res) << "request " << i << " not answered while 6 streams are open";
    EXPECT_EQ(res->status, 200);
    auto health = quick->Get("/healthz");
    ASSERT_TRUE(health);
    EXPECT_EQ(health->status, 200);
  }
  auto metrics = quick->Get("/metrics");
  ASSERT_TRUE(metrics);
  EXPECT_NE(metrics->body.find("voxd_event_streams_open 6\n"), std::string::npos) << metrics->body;
  int status = 0;
  const std::vector<Event> refused = read_events(server_->port(), id, &status);
  EXPECT_EQ(status, 503);
  EXPECT_TRUE(refused.empty());
  for (auto& t : readers) t.join();
  const json done = expect_json(http().Get(("/v1/jobs/" + id).c_str()), 200, "JobStatus");
  for (const auto& events : seen) expect_well_formed(events, done);
  // Closed streams are counted out (just after their last bytes went).
  bool closed = false;
  for (int i = 0; i < 100 && !closed; ++i, std::this_thread::sleep_for(std::chrono::milliseconds(20)))
    closed = quick->Get("/metrics")->body.find("voxd_event_streams_open 0\n") != std::string::npos;
  EXPECT_TRUE(closed) << quick->Get("/metrics")->body;
}

// Replicas on one Redis: every replica streams every job, the one that runs
// it and the one that does not, with the same stages, analyses and end.
TEST_F(JobEventsTest, EveryReplicaOnOneRedisStreamsTheSameJob) {
  RedisProcess redis(dir_ + "/redis");
  std::vector<std::unique_ptr<ServerProcess>> replicas;
  for (int i = 0; i < 2; ++i)
    replicas.push_back(std::make_unique<ServerProcess>(dir_ + "/replica" + std::to_string(i),
                                                       std::vector<std::string>{"--redis", redis.url(), "--workers", "1"}));
  auto client = make_client(replicas[0]->port());
  const std::string id =
      expect_json(post_multipart(*client, "/v1/jobs", hollow_box(), "box.stl",
                                 R"({"grid": {"resolution": 360}, "analyses": [{"kind": "analysis", "min_wall": 1}, {"kind": "radiography", "axis": "x"}]})"),
                  202, "JobStatus")
          .at("id");
  std::vector<std::vector<Event>> seen(2);
  std::vector<std::thread> readers;
  for (std::size_t i = 0; i < 2; ++i)
    readers.emplace_back([&, i, port = replicas[i]->port()] { seen[i] = read_events(port, id); });
  for (auto& t : readers) t.join();
  const json done = expect_json(client->Get(("/v1/jobs/" + id).c_str()), 200, "JobStatus");
  ASSERT_EQ(done.at("state"), "succeeded");
  for (std::size_t i = 0; i < 2; ++i) {
    SCOPED_TRACE("replica " + std::to_string(i));
    expect_well_formed(seen[i], done);
    std::size_t analyses = 0, staged = 0;
    for (const auto& e : seen[i]) {
      analyses += e.name == "analysis";
      staged += e.name == "progress" && e.data.at("stage").is_string();
    }
    std::string trace;
    for (const auto& e : seen[i])
      if (e.name != "progress") trace += e.name + " " + (e.name == "analysis" ? e.data.dump() : e.data.value("state", "")) + "\n";
    EXPECT_EQ(analyses, 2u) << trace;
    EXPECT_GT(staged, 0u) << "no stage seen while the job ran";
  }
  for (auto& r : replicas) EXPECT_EQ(r->stop(), 0) << r->log();
}

}  // namespace
}  // namespace voxd::test
