#pragma once
// Jobs waiting for a worker, by id: submit, take, ack, cancel. The job
// engine's workers only talk to this interface; the embedded implementation
// is in-process (InProcessJobQueue below). A shared backend
// (server/redis/redis_job_queue.h: replicas taking from one Redis stream)
// implements the same calls: take() then hands out a job another replica
// accepted, or one whose worker died, under a lease that ack() ends.
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace voxd::server {

struct TakenJob {
  std::string id;
  // How many times the job was handed out, this time included: more than
  // one when a worker before this one stopped (its replica died).
  int deliveries = 1;
};

class JobQueue {
 public:
  virtual ~JobQueue() = default;
  // Queues a job; false when the queue holds its capacity already (or is closed).
  virtual bool submit(const std::string& id) = 0;
  // The next job, waiting up to `wait` for one; nullopt when none came or
  // the queue is closed (closed() tells which).
  virtual std::optional<TakenJob> take(std::chrono::milliseconds wait) = 0;
  virtual bool closed() const = 0;
  // The worker that took `id` is done with it (succeeded, failed or
  // cancelled). Never throws: a shared queue that cannot be told now lets
  // the lease lapse instead.
  virtual void ack(const std::string& id) = 0;
  // The worker that took `id` gives it back unfinished (this process stops,
  // or the shared backend went away): the next take, here or in another
  // replica, gets it. Never throws, like ack.
  virtual void release(const std::string& id) { ack(id); }
  // Keeps the leases of the jobs taken here alive; the engine calls it about
  // every 100 ms. Nothing to do in-process.
  virtual void renew_leases() {}
  // Replaces the job taken here by `tasks` (a huge job's slab tasks,
  // server/jobs/slab_tasks.h) in one step: the tasks are queued, past the
  // capacity (their job was admitted already), and the job's own entry
  // ends. A job is split once: for one split already (its entry handed out
  // twice), only the entry ends. Throws BackendUnavailable; only a shared
  // queue splits (std::logic_error here).
  virtual void split(const std::string& id, const std::vector<std::string>& tasks) {
    (void)tasks;
    throw std::logic_error("job " + id + ": only a shared queue splits jobs");
  }
  // Removes a job that waits; false when it is not waiting (taken, unknown).
  virtual bool cancel(const std::string& id) = 0;
  // Jobs waiting.
  virtual std::size_t depth() const = 0;
  // Takes no more, wakes every take(), and hands back the jobs that waited
  // for this process (none for a shared queue: they wait for other replicas).
  virtual std::vector<std::string> close() = 0;
};

class InProcessJobQueue final : public JobQueue {
 public:
  explicit InProcessJobQueue(std::size_t capacity) : capacity_(capacity) {}
  bool submit(const std::string& id) override;
  std::optional<TakenJob> take(std::chrono::milliseconds wait) override;
  bool closed() const override;
  void ack(const std::string&) override {}
  bool cancel(const std::string& id) override;
  std::size_t depth() const override;
  std::vector<std::string> close() override;

 private:
  const std::size_t capacity_;
  mutable std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<std::string> waiting_;
  bool closed_ = false;
};

}  // namespace voxd::server
