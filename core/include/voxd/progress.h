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

  // `fraction` of the current span (the whole job unless set_span narrowed
  // it), so stages that each report 0..1 add up to one steady progress bar.
  void set_progress(double fraction) {
    const double b = span_begin_.load(std::memory_order_relaxed), e = span_end_.load(std::memory_order_relaxed);
    progress_.store(b + (e - b) * fraction, std::memory_order_relaxed);
  }
  double progress() const { return progress_.load(std::memory_order_relaxed); }
  // Maps the following set_progress calls onto [begin, end] of the job.
  void set_span(double begin, double end) {
    span_begin_.store(begin, std::memory_order_relaxed);
    span_end_.store(end, std::memory_order_relaxed);
  }
  double span_begin() const { return span_begin_.load(std::memory_order_relaxed); }
  double span_end() const { return span_end_.load(std::memory_order_relaxed); }

 private:
  std::atomic<bool> cancel_{false};
  std::atomic<double> progress_{0.0};
  std::atomic<double> span_begin_{0.0}, span_end_{1.0};
};

}  // namespace voxd
