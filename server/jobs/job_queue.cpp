#include "server/jobs/job_queue.h"

#include <algorithm>

namespace voxd::server {

bool InProcessJobQueue::submit(const std::string& id) {
  {
    std::lock_guard lock(mutex_);
    if (closed_ || waiting_.size() >= capacity_) return false;
    waiting_.push_back(id);
  }
  ready_.notify_one();
  return true;
}

std::optional<TakenJob> InProcessJobQueue::take(std::chrono::milliseconds wait) {
  std::unique_lock lock(mutex_);
  ready_.wait_for(lock, wait, [&] { return closed_ || !waiting_.empty(); });
  if (closed_ || waiting_.empty()) return std::nullopt;
  TakenJob taken{std::move(waiting_.front())};
  waiting_.pop_front();
  return taken;
}

bool InProcessJobQueue::closed() const {
  std::lock_guard lock(mutex_);
  return closed_;
}

bool InProcessJobQueue::cancel(const std::string& id) {
  std::lock_guard lock(mutex_);
  const auto it = std::find(waiting_.begin(), waiting_.end(), id);
  if (it == waiting_.end()) return false;
  waiting_.erase(it);
  return true;
}

std::size_t InProcessJobQueue::depth() const {
  std::lock_guard lock(mutex_);
  return waiting_.size();
}

std::vector<std::string> InProcessJobQueue::close() {
  std::vector<std::string> left;
  {
    std::lock_guard lock(mutex_);
    closed_ = true;
    left.assign(waiting_.begin(), waiting_.end());
    waiting_.clear();
  }
  ready_.notify_all();
  return left;
}

}  // namespace voxd::server
