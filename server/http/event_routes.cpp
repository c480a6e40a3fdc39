#include "server/http/routes.h"

#include <algorithm>
#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include <httplib.h>

#include "server/http/connection_server.h"
#include "server/http/job_event_stream.h"
#include "server/http/job_lookup.h"
#include "server/http/metrics.h"
#include "server/http/route_table.h"
#include "server/http/stream_requests.h"
#include "server/jobs/job_manager.h"

namespace voxd::server {
namespace {

using Clock = std::chrono::steady_clock;

// How often a stream looks at its job besides being woken by a change: the
// progress bar's refresh, and how soon a change made on another replica
// shows.
constexpr std::chrono::milliseconds kPollInterval{250};
// A comment this often on a quiet stream, before proxies time it out.
constexpr std::chrono::seconds kKeepAlive{15};

}  // namespace

void install_event_routes(RouteTable& routes, JobManager& jobs, Metrics& metrics) {
  // Runs on one of the connection server's stream threads, never an HTTP
  // thread (connection_server.h), for as long as the job runs.
  routes.get(kJobPath + "/events", [&jobs, &metrics](const httplib::Request& req, httplib::Response& res) {
    const std::string id = req.matches[1];
    // Counted before the first look, so a change between the two is seen.
    const std::uint64_t seen = jobs.wait_for_change(~std::uint64_t{0}, std::chrono::milliseconds(0));
    const auto job = visible_job(jobs, id);
    if (!job) throw unknown_job(id);
    // An EventSource reconnects by itself after the stream ends, saying the
    // last event it had: for a job that has ended there is nothing more,
    // and 204 is what tells an EventSource to stop.
    if (req.has_header("Last-Event-ID") && finished(job->state)) {
      res.status = 204;
      return;
    }
    // Lives as long as the response's provider: the stream is open.
    struct State {
      explicit State(Metrics& m) : metrics(m) { metrics.stream_opened(); }
      ~State() { metrics.stream_closed(); }
      State(const State&) = delete;
      State& operator=(const State&) = delete;
      Metrics& metrics;
      JobEventStream stream;
      std::string pending;
      std::uint64_t seen = 0;
      Clock::time_point last_write = Clock::now();
    };
    auto state = std::make_shared<State>(metrics);
    state->pending = state->stream.start(*job);
    state->seen = seen;
    res.set_header("Cache-Control", "no-cache");
    res.set_header("X-Accel-Buffering", "no");  // nginx: pass each event on at once
    res.set_chunked_content_provider("text/event-stream", [&jobs, id, state](std::size_t, httplib::DataSink& sink) {
      try {
        if (!state->pending.empty()) {
          if (!sink.write(state->pending.data(), state->pending.size())) return false;
          state->pending.clear();
          state->last_write = Clock::now();
        }
        if (state->stream.ended()) {
          sink.done();
          return true;
        }
        if (request_client_gone()) return false;
        state->seen = jobs.wait_for_change(state->seen, kPollInterval);
        const auto now = jobs.get(id);
        state->pending = now ? state->stream.update(*now) : state->stream.gone(id);
        if (state->pending.empty() && Clock::now() - state->last_write >= kKeepAlive)
          state->pending = JobEventStream::keep_alive();
        return true;
      } catch (const std::exception&) {
        return false;  // the backend went away: the client reconnects
      }
    });
  });
}

}  // namespace voxd::server
