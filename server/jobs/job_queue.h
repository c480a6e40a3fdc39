#pragma once
// Jobs waiting for a worker, by id: submit, take, ack, cancel. The job
// engine's workers only talk to this interface; the embedded implementation
// is in-process (InProcessJobQueue below). A shared backend (replicas taking
// from one Redis list) implements the same calls: take() then hands out a
// job another replica accepted, and ack() ends its lease.
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace voxd::server {

class JobQueue {
 public:
  virtual ~JobQueue() = default;
  // Queues a job; false when the queue holds its capacity already (or is closed).
  virtual bool submit(const std::string& id) = 0;
  // The next job, waiting for one; nullopt once the queue is closed.
  virtual std::optional<std::string> take() = 0;
  // The worker that took `id` is done with it (succeeded, failed or cancelled).
  virtual void ack(const std::string& id) = 0;
  // Removes a job that waits; false when it is not waiting (taken, unknown).
  virtual bool cancel(const std::string& id) = 0;
  // Jobs waiting.
  virtual std::size_t depth() const = 0;
  // Takes no more, wakes every take(), and hands back the jobs that waited.
  virtual std::vector<std::string> close() = 0;
};

class InProcessJobQueue final : public JobQueue {
 public:
  explicit InProcessJobQueue(std::size_t capacity) : capacity_(capacity) {}
  bool submit(const std::string& id) override;
  std::optional<std::string> take() override;
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
