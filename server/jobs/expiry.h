#pragma once
// When finished jobs go: `ttl` after they finished, swept by a background
// timer every tenth of the ttl (at least 1 s, at most 60 s), so a job lives
// between ttl and ttl + period. The sweep itself (what removing a job means)
// belongs to the job engine; a shared backend can keep this timer or let its
// store expire records itself.
#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>

#include "server/jobs/job.h"

namespace voxd::server {

// Whether a job has outlived its ttl at `now`. Jobs that have not finished
// never expire.
bool expired(const JobSnapshot& job, std::chrono::system_clock::time_point now, std::chrono::seconds ttl);

class ExpiryTimer {
 public:
  // Starts calling `sweep` every period, on its own thread.
  ExpiryTimer(std::chrono::seconds ttl, std::function<void()> sweep);
  ~ExpiryTimer();  // stops, waiting for a sweep under way
  ExpiryTimer(const ExpiryTimer&) = delete;
  ExpiryTimer& operator=(const ExpiryTimer&) = delete;

  static std::chrono::seconds period_for(std::chrono::seconds ttl);

 private:
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace voxd::server
