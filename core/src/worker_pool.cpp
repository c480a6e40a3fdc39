#include "worker_pool.h"

#include <pthread.h>

#include <memory>
#include <mutex>
#include <thread>
#include <vector>

namespace voxd::detail {

// A kept thread: idle (on the idle list, no team), handed a team's work
// (not yet awake to it), or busy running it.
struct PoolWorker {
  std::condition_variable wake;
  WorkerHelpers* team = nullptr;
  bool busy = false;
};

class WorkerPool {
 public:
  // Never destroyed: its threads wait on it until the process ends, and a
  // static's destructor would pull it from under them. A child of fork()
  // (a host embedding the engine may fork) has none of its threads, and
  // may have been forked while one held its mutex: it takes a new pool of
  // its own, and keeps the parent's copy as it was.
  static WorkerPool& instance() {
    static const bool made = [] {
      current_ = new WorkerPool;
      pthread_atfork(nullptr, nullptr, [] {
        WorkerPool* const fresh = new WorkerPool;
        fresh->forked_from_ = current_;
        current_ = fresh;
      });
      return true;
    }();
    (void)made;
    return *current_;
  }

  void hand_out(WorkerHelpers& team, int count) {
    team.handed_.reserve(static_cast<std::size_t>(count));  // may throw, before any is handed the work
    {
      std::lock_guard lock(mutex_);
      while (count > 0 && !idle_.empty()) {
        PoolWorker* w = idle_.back();  // the last to finish: its caches are the warmest
        idle_.pop_back();
        w->team = &team;
        ++team.running_;
        team.handed_.push_back(w);
        --count;
      }
    }
    // Notified outside the lock, so a woken thread does not wait for it.
    // A worker is never destroyed, so its condition variable outlives this.
    for (PoolWorker* w : team.handed_) w->wake.notify_one();
    for (; count > 0; --count)
      if (!start_worker(team)) break;  // the process's thread limit: the work has the helpers it has
  }

  // Takes back the work from helpers not yet awake to it (the caller has
  // claimed every piece by now, so there is nothing left for them: on a
  // virtual machine waking an idle core can take longer than a small
  // loop), then waits for the busy ones.
  void wait(WorkerHelpers& team) {
    std::unique_lock lock(mutex_);
    for (PoolWorker* w : team.handed_)
      if (w->team == &team && !w->busy) {
        w->team = nullptr;
        idle_.push_back(w);
        --team.running_;
      }
    team.all_back_.wait(lock, [&] { return team.running_ == 0; });
  }

  int kept() {
    std::lock_guard lock(mutex_);
    return static_cast<int>(all_.size());
  }

 private:
  // A new thread handed `team`'s work, kept afterwards; false if it could
  // not be started (nothing of it is left behind then).
  bool start_worker(WorkerHelpers& team) noexcept {
    PoolWorker* w = nullptr;
    try {
      auto worker = std::make_unique<PoolWorker>();
      worker->team = &team;
      w = worker.get();
      std::lock_guard lock(mutex_);
      // Room on the idle list for every kept thread, so that going idle
      // (serve, wait) never allocates.
      idle_.reserve(all_.size() + 1);
      all_.push_back(std::move(worker));
      team.handed_.push_back(w);  // reserved: does not throw
      ++team.running_;
    } catch (...) {
      return false;
    }
    try {
      std::thread(&WorkerPool::serve, this, w).detach();
      return true;
    } catch (...) {
      std::lock_guard lock(mutex_);
      --team.running_;
      team.handed_.pop_back();
      std::erase_if(all_, [&](const std::unique_ptr<PoolWorker>& kept) { return kept.get() == w; });
      return false;
    }
  }

  void serve(PoolWorker* self) {
    pthread_setname_np(pthread_self(), "voxd-worker");
    std::unique_lock lock(mutex_);
    for (;;) {
      self->wake.wait(lock, [&] { return self->team != nullptr; });
      WorkerHelpers* const team = self->team;
      self->busy = true;
      lock.unlock();
      (*team->work_)();
      lock.lock();
      self->busy = false;
      self->team = nullptr;
      idle_.push_back(self);
      // Under the lock: the caller cannot leave wait(), and destroy the
      // team, before this notify is done.
      if (--team->running_ == 0) team->all_back_.notify_one();
    }
  }

  static inline WorkerPool* current_ = nullptr;
  std::mutex mutex_;
  std::vector<std::unique_ptr<PoolWorker>> all_;  // a thread started for each
  std::vector<PoolWorker*> idle_;
  WorkerPool* forked_from_ = nullptr;  // in a child of fork(), the parent's pool (kept reachable, never used)
};

WorkerHelpers::WorkerHelpers(int count, const std::function<void()>& work) : work_(&work) {
  if (count > 0) WorkerPool::instance().hand_out(*this, count);
}

WorkerHelpers::~WorkerHelpers() { wait(); }

void WorkerHelpers::wait() {
  if (!handed_.empty()) WorkerPool::instance().wait(*this);
}

int kept_worker_threads() { return WorkerPool::instance().kept(); }

}  // namespace voxd::detail
