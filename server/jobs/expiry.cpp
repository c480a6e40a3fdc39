#include "server/jobs/expiry.h"

#include <algorithm>

#include "server/jobs/job_record.h"

namespace voxd::server {

bool expired(const JobSnapshot& job, std::chrono::system_clock::time_point now, std::chrono::seconds ttl) {
  return finished(job.state) && !job.finished_at.empty() && parse_time(job.finished_at) < now - ttl;
}

std::chrono::seconds ExpiryTimer::period_for(std::chrono::seconds ttl) {
  return std::clamp<std::chrono::seconds>(ttl / 10, std::chrono::seconds(1), std::chrono::seconds(60));
}

ExpiryTimer::ExpiryTimer(std::chrono::seconds ttl, std::function<void()> sweep) {
  thread_ = std::thread([this, period = period_for(ttl), sweep = std::move(sweep)] {
    std::unique_lock lock(mutex_);
    while (!wake_.wait_for(lock, period, [&] { return stopping_; })) {
      lock.unlock();
      sweep();
      lock.lock();
    }
  });
}

ExpiryTimer::~ExpiryTimer() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

}  // namespace voxd::server
