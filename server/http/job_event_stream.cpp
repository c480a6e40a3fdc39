#include "server/http/job_event_stream.h"

#include <algorithm>
#include <cmath>

#include "server/http/job_status.h"
#include "server/jobs/job_record.h"

namespace voxd::server {

using nlohmann::json;

namespace {

json stage_json(const std::string& stage) { return stage.empty() ? json(nullptr) : json(stage); }
// Four decimals: a bar's hundredth of a percent, without float noise.
double rounded(double progress) { return std::round(progress * 1e4) / 1e4; }

}  // namespace

std::string JobEventStream::event(const char* name, const json& data) {
  // One line of JSON: no newline can end the data field early.
  return "id: " + std::to_string(next_id_++) + "\nevent: " + name +
         "\ndata: " + data.dump(-1, ' ', false, json::error_handler_t::replace) + "\n\n";
}

std::string JobEventStream::start(const JobSnapshot& now) {
  state_ = now.state;
  progress_ = now.progress;
  stage_ = now.state == JobState::running ? now.stage : std::string();
  // What the first event shows as ready needs no event of its own.
  if (now.analyses.is_array())
    for (const auto& entry : now.analyses) {
      const std::string state = entry.value("state", "");
      analysis_sent_.push_back(state == "ready" || state == "failed");
    }
  // How long a client's EventSource waits before it reconnects.
  std::string out = "retry: 1000\n\n" + event("job", job_status_json(now));
  if (finished(now.state)) {
    out += event("end", job_status_json(now));
    ended_ = true;
  }
  return out;
}

std::string JobEventStream::update(const JobSnapshot& now) {
  if (ended_) return {};
  std::string out;
  // The bar only rises, also when another replica takes over a job whose
  // replica died and runs it again from the start.
  const double progress = finished(now.state) ? now.progress : std::max(progress_, now.progress);
  const std::string stage = now.state == JobState::running ? now.stage : std::string();
  if (now.state != state_ && !finished(now.state)) {
    out += event("state", {{"state", to_string(now.state)}, {"progress", rounded(progress)}, {"stage", stage_json(stage)}});
    state_ = now.state;
    progress_ = progress;
    stage_ = stage;
  } else if (!finished(now.state) && (progress >= progress_ + 0.001 || stage != stage_)) {
    // Smaller steps wait until the bar moves visibly.
    out += event("progress", {{"progress", rounded(progress)}, {"stage", stage_json(stage)}});
    progress_ = progress;
    stage_ = stage;
  }
  // Each requested analysis once, when it is ready or failed.
  if (now.analyses.is_array()) {
    if (analysis_sent_.size() < now.analyses.size()) analysis_sent_.resize(now.analyses.size(), false);
    for (std::size_t i = 0; i < now.analyses.size(); ++i) {
      const json& entry = now.analyses[i];
      const std::string state = entry.value("state", "");
      if (analysis_sent_[i] || (state != "ready" && state != "failed")) continue;
      analysis_sent_[i] = true;
      json data = analysis_status_entry(entry, now.id);
      data["index"] = i;
      out += event("analysis", data);
    }
  }
  if (finished(now.state)) {
    out += event("end", job_status_json(now));
    state_ = now.state;
    ended_ = true;
  }
  return out;
}

std::string JobEventStream::gone(const std::string& id) {
  if (ended_) return {};
  ended_ = true;
  return event("gone", {{"id", id}, {"detail", "the job was deleted or has expired"}});
}

}  // namespace voxd::server
