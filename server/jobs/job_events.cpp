#include "server/jobs/job_events.h"

#include <spdlog/spdlog.h>

namespace voxd::server {

void JobEvents::announce(const JobSnapshot& s) {
  if (!listener_) return;
  std::lock_guard lock(pending_mutex_);
  pending_.push_back(s);
}

void JobEvents::deliver() {
  if (!listener_) return;
  std::lock_guard delivering(delivery_mutex_);
  for (;;) {
    JobSnapshot event;
    {
      std::lock_guard lock(pending_mutex_);
      if (pending_.empty()) return;
      event = std::move(pending_.front());
      pending_.pop_front();
    }
    try {
      listener_(event);
    } catch (const std::exception& e) {
      spdlog::error("job state listener failed: {}", e.what());
    }
  }
}

}  // namespace voxd::server
