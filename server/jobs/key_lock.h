#pragma once
// The lock of one kept result's key (server/jobs/job_analyses.cpp): like a
// mutex, but another thread than the one that took it may let it go. A
// result's write goes on after the request that computed it has answered
// (server/jobs/background_save.h), and holds the key until it ends.
#include <condition_variable>
#include <mutex>

namespace voxd::server {

class KeyLock {
 public:
  void lock() {
    std::unique_lock guard(mutex_);
    free_.wait(guard, [&] { return !held_; });
    held_ = true;
  }
  void unlock() {
    {
      std::lock_guard guard(mutex_);
      held_ = false;
    }
    free_.notify_one();
  }

 private:
  std::mutex mutex_;
  std::condition_variable free_;
  bool held_ = false;
};

}  // namespace voxd::server
