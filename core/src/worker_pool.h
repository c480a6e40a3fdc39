#pragma once
// The threads that parallel_for and the ordered pipeline share work with,
// kept for the life of the process. Starting and joining a thread costs
// about 25 microseconds on the development VM, on the calling thread, so a
// loop on 16 threads paid some 400 microseconds before its first piece ran
// on the last thread: as much as a whole loop of the small stages (parts
// and voids, thickness regions), which run a few dozen loops a job. A
// kept thread is woken instead, and a caller that has claimed every piece
// before a helper woke does not wait for it
// (bench/loop_overhead_bench.cpp).
//
// Not a work-stealing scheduler (such as oneTBB): a helper runs exactly the
// work it was handed, which claims pieces in index order, and nothing else
// while it waits. The ordered pipeline's producers wait for the consumer on
// a condition variable; a thread that stole unrelated tasks while waiting
// could deadlock there, and the stages' results must not depend on which
// thread ran what.
#include <condition_variable>
#include <functional>
#include <vector>

namespace voxd::detail {

struct PoolWorker;

// Up to `count` threads other than the caller's running `work` (once each)
// from construction on. Idle kept threads are handed the work and woken;
// the rest are started, and kept afterwards (a process keeps as many as it
// ever used at once). wait(), or the destructor, takes the work back from
// those not yet awake to it and waits for the others to return from it:
// call it once the caller's own share has left nothing to do. Where a
// thread cannot be started the work has fewer helpers, so it must not
// depend on how many run it; and it must not throw.
class WorkerHelpers {
 public:
  WorkerHelpers(int count, const std::function<void()>& work);
  ~WorkerHelpers();
  WorkerHelpers(const WorkerHelpers&) = delete;
  WorkerHelpers& operator=(const WorkerHelpers&) = delete;

  // Waits until each helper has returned from the work (again: at once).
  void wait();
  // How many threads were handed the work (at most `count`; a helper not
  // yet awake when the caller waits gives it back unrun).
  int handed() const { return static_cast<int>(handed_.size()); }

 private:
  friend class WorkerPool;
  const std::function<void()>* work_;
  std::vector<PoolWorker*> handed_;
  int running_ = 0;  // helpers handed the work and not back (the pool's mutex guards it)
  std::condition_variable all_back_;
};

// Threads kept by the pool so far, idle or busy: for tests.
int kept_worker_threads();

}  // namespace voxd::detail
