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

std::optional<std::string> InProcessJobQueue::take() {
  std::unique_lock lock(mutex_);
  ready_.wait(lock, [&] { return closed_ || !waiting_.empty(); });
  if (closed_) return std::nullopt;
  std::string id = std::move(waiting_.front());
  waiting_.pop_front();
  return id;
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
