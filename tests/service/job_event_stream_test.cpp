// The events JobEventStream makes from a job's successive snapshots, which
// may come from different views (this replica's table, Redis's record a
// moment older): progress never goes back, each analysis is sent once, the
// end closes the stream.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "server/http/job_event_stream.h"
#include "server/http/routes.h"
#include "server/http/stream_requests.h"

namespace voxd::server {
namespace {

using nlohmann::json;

struct Sent {
  std::string name;
  json data;
};

std::vector<Sent> parse(const std::string& text) {
  std::vector<Sent> out;
  std::size_t at = 0;
  for (std::size_t cut; (cut = text.find("\n\n", at)) != std::string::npos; at = cut + 2) {
    const std::string block = text.substr(at, cut - at);
    Sent s;
    std::size_t line_at = 0;
    for (std::size_t end; line_at <= block.size(); line_at = end + 1) {
      end = block.find('\n', line_at);
      if (end == std::string::npos) end = block.size();
      const std::string line = block.substr(line_at, end - line_at);
      if (line.rfind("event: ", 0) == 0) s.name = line.substr(7);
      if (line.rfind("data: ", 0) == 0) s.data = json::parse(line.substr(6));
    }
    if (!s.name.empty()) out.push_back(s);
  }
  return out;
}

JobSnapshot job(JobState state, double progress, const std::string& stage, std::vector<std::string> analyses) {
  JobSnapshot s;
  s.id = std::string(32, 'a');
  s.state = state;
  s.progress = progress;
  s.stage = stage;
  s.analyses = json::array();
  for (const auto& a : analyses) s.analyses.push_back({{"request", {{"kind", "analysis"}}}, {"url", "/u"}, {"state", a}, {"error", nullptr}});
  return s;
}

TEST(JobEventStream, ProgressOnlyRisesAndEachAnalysisIsSentOnceWhateverViewComesNext) {
  JobEventStream stream;
  auto first = parse(stream.start(job(JobState::queued, 0, "", {"pending", "pending"})));
  ASSERT_EQ(first.size(), 1u);
  EXPECT_EQ(first[0].name, "job");

  auto running = parse(stream.update(job(JobState::running, 0.2, "voxelize", {"pending", "pending"})));
  ASSERT_EQ(running.size(), 1u);
  EXPECT_EQ(running[0].name, "state");
  EXPECT_EQ(running[0].data.at("stage"), "voxelize");

  auto ready = parse(stream.update(job(JobState::running, 0.6, "analysis: analysis", {"ready", "pending"})));
  ASSERT_EQ(ready.size(), 2u);
  EXPECT_EQ(ready[0].name, "progress");
  EXPECT_EQ(ready[1].name, "analysis");
  EXPECT_EQ(ready[1].data.at("index"), 0);

  // An older view: lower progress, the analysis pending again. Nothing.
  EXPECT_EQ(stream.update(job(JobState::running, 0.5, "analysis: analysis", {"pending", "pending"})), "");
  // Too small a step to send.
  EXPECT_EQ(stream.update(job(JobState::running, 0.6004, "analysis: analysis", {"ready", "pending"})), "");

  auto end = parse(stream.update(job(JobState::succeeded, 1.0, "", {"ready", "ready"})));
  ASSERT_EQ(end.size(), 2u);
  EXPECT_EQ(end[0].name, "analysis");
  EXPECT_EQ(end[0].data.at("index"), 1);
  EXPECT_EQ(end[1].name, "end");
  EXPECT_EQ(end[1].data.at("state"), "succeeded");
  EXPECT_TRUE(stream.ended());
  EXPECT_EQ(stream.update(job(JobState::succeeded, 1.0, "", {"ready", "ready"})), "");
  EXPECT_EQ(stream.gone(std::string(32, 'a')), "");
}

TEST(JobEventStream, AFinishedJobIsTheJobAndItsEndAndAnalysesShownFirstAreNotSentAgain) {
  JobEventStream finished;
  auto sent = parse(finished.start(job(JobState::failed, 0.3, "", {"failed"})));
  ASSERT_EQ(sent.size(), 2u);
  EXPECT_EQ(sent[0].name, "job");
  EXPECT_EQ(sent[1].name, "end");
  EXPECT_TRUE(finished.ended());

  JobEventStream late;
  late.start(job(JobState::running, 0.7, "analysis: radiography", {"ready", "pending"}));
  auto next = parse(late.update(job(JobState::running, 0.7, "analysis: radiography", {"ready", "ready"})));
  ASSERT_EQ(next.size(), 1u);
  EXPECT_EQ(next[0].name, "analysis");
  EXPECT_EQ(next[0].data.at("index"), 1);
}

TEST(JobEventStream, ADeletedJobIsGoneAndTheStreamEnds) {
  JobEventStream stream;
  stream.start(job(JobState::running, 0.1, "voxelize", {}));
  auto gone = parse(stream.gone(std::string(32, 'a')));
  ASSERT_EQ(gone.size(), 1u);
  EXPECT_EQ(gone[0].name, "gone");
  EXPECT_EQ(gone[0].data.at("id"), std::string(32, 'a'));
  EXPECT_TRUE(stream.ended());
}

// The connection server sends exactly these request lines to the stream
// threads; anything else (even close to it) goes to the HTTP threads.
TEST(EventStreamRequest, OnlyAGetOfAJobsEventsIsAStream) {
  const std::string id = "0123456789abcdef0123456789abcdef";
  EXPECT_TRUE(is_event_stream_request("GET /v1/jobs/" + id + "/events HTTP/1.1"));
  EXPECT_TRUE(is_event_stream_request("GET /v1/jobs/" + id + "/events?x=1 HTTP/1.1"));
  EXPECT_TRUE(is_event_stream_request("GET /v1/jobs/" + id + "/events"));  // a head cut at the peek
  EXPECT_FALSE(is_event_stream_request("POST /v1/jobs/" + id + "/events HTTP/1.1"));
  EXPECT_FALSE(is_event_stream_request("GET /v1/jobs/" + id + " HTTP/1.1"));
  EXPECT_FALSE(is_event_stream_request("GET /v1/jobs/" + id + "/events/more HTTP/1.1"));
  EXPECT_FALSE(is_event_stream_request("GET /v1/jobs/" + id + "/eventsx HTTP/1.1"));
  EXPECT_FALSE(is_event_stream_request("GET /v1/jobs/0123456789ABCDEF0123456789abcdef/events HTTP/1.1"));
  EXPECT_FALSE(is_event_stream_request("GET /v1/jobs/0123/events HTTP/1.1"));
  EXPECT_FALSE(is_event_stream_request("GET /x/v1/jobs/" + id + "/events HTTP/1.1"));
  EXPECT_FALSE(is_event_stream_request(""));
  EXPECT_FALSE(is_event_stream_request("GET"));
  // As httplib reads the line (issue #37, finding 2): the path decoded, runs
  // of spaces and tabs around the words.
  EXPECT_TRUE(is_event_stream_request("GET /v1/jobs/%" + std::string("61") + id.substr(1) + "/events HTTP/1.1"));
  EXPECT_TRUE(is_event_stream_request("GET /v1/jobs/" + id + "/event%73 HTTP/1.1"));
  EXPECT_TRUE(is_event_stream_request("GET /v1/jobs/" + id + "%2Fevents HTTP/1.1"));
  EXPECT_TRUE(is_event_stream_request("GET  \t/v1/jobs/" + id + "/events\t  HTTP/1.1"));
  EXPECT_FALSE(is_event_stream_request("GET /v1/jobs/" + id + "/events%3F HTTP/1.1"));
  // httplib routes ".../events#x" to the stream (it drops the fragment);
  // the gate refuses such a line, and the test here still classifies it so.
  EXPECT_TRUE(is_event_stream_request("GET /v1/jobs/" + id + "/events#x HTTP/1.1"));
  EXPECT_TRUE(is_event_stream_request("GET /v1/jobs/" + id + "/events#?x=1 HTTP/1.1"));
  EXPECT_FALSE(is_event_stream_request("GET /v1/jobs/" + id + "/events%23 HTTP/1.1"));
  EXPECT_FALSE(is_event_stream_request("HEAD /v1/jobs/" + id + "/events HTTP/1.1"));
}

}  // namespace
}  // namespace voxd::server
