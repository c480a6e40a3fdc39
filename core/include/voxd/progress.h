#pragma once
// Progress reporting and cooperative cancellation, shared between a running
// engine stage and whoever watches it (a CLI, an HTTP worker).
#include <atomic>

namespace voxd {

class JobControl {
 public:
  void request_cancel() { cancel_.store(true, std::memory_order_relaxed); }
  bool cancel_requested() const { return cancel_.load(std::memory_order_relaxed); }
  // Throws Error(cancelled) if cancellation was requested. Engines call this
  // between units of work small enough that cancel is prompt (< ~50 ms).
  void check_cancelled() const;

  void set_progress(double fraction) { progress_.store(fraction, std::memory_order_relaxed); }
  double progress() const { return progress_.load(std::memory_order_relaxed); }

 private:
  std::atomic<bool> cancel_{false};
  std::atomic<double> progress_{0.0};
};

}  // namespace voxd
