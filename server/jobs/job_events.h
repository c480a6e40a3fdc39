#pragma once
// Job state changes handed to a listener (logs, metrics; later, server-sent
// events) in the order they happen, one at a time, never under the job
// table's lock: announce() queues an event where the change is made (under
// that lock, so the order is the table's), deliver() hands the queued ones
// on from a thread that holds no lock. A worker that starts a job the instant
// it is queued must not report "running" before the submitter reports
// "queued". Thread-safe.
#include <deque>
#include <functional>
#include <mutex>

#include "server/jobs/job.h"

namespace voxd::server {

class JobEvents {
 public:
  explicit JobEvents(std::function<void(const JobSnapshot&)> listener) : listener_(std::move(listener)) {}
  void announce(const JobSnapshot& s);
  void deliver();

 private:
  std::function<void(const JobSnapshot&)> listener_;
  std::mutex pending_mutex_;
  std::deque<JobSnapshot> pending_;  // guarded by pending_mutex_
  std::mutex delivery_mutex_;        // one deliverer at a time, in order
};

}  // namespace voxd::server
