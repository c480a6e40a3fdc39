#pragma once
// One job's server-sent events (GET /v1/jobs/{id}/events), made from its
// successive snapshots, so the stream says the same thing whichever replica
// serves it and however often it looks:
//   job       the job as it is when the client connects (GET /v1/jobs/{id})
//   state     {"state", "progress", "stage"} when the state changes
//   progress  {"progress", "stage"} when either moves; progress never goes back
//   analysis  {"index", "request", "url", "state", "error"} when one of the
//             job JSON's analyses is ready or failed
//   end       the job as it ended; the stream ends after it
//   gone      {"id", "detail"} when the job was deleted or expired; the end too
// Every event has an increasing id. A late subscriber gets "job" first (and,
// for a finished job, "end" right after).
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "server/jobs/job.h"

namespace voxd::server {

class JobEventStream {
 public:
  // The first events, for the job as it is now.
  std::string start(const JobSnapshot& now);
  // The events for what changed since the previous snapshot ("" for none).
  std::string update(const JobSnapshot& now);
  // The job is no longer there.
  std::string gone(const std::string& id);
  // A comment line that keeps idle proxies from closing the stream.
  static std::string keep_alive() { return ": keep-alive\n\n"; }
  // Whether the last event was sent: the stream closes.
  bool ended() const { return ended_; }

 private:
  std::string event(const char* name, const nlohmann::json& data);

  std::uint64_t next_id_ = 1;
  JobState state_ = JobState::queued;
  double progress_ = 0.0;
  std::string stage_;
  // Analyses already sent as ready or failed (by index): each is sent once,
  // also when a later snapshot, read from another replica's or Redis's
  // slightly older view, still says pending.
  std::vector<bool> analysis_sent_;
  bool ended_ = false;
};

}  // namespace voxd::server
