#pragma once
// Progress reporting and cooperative cancellation, shared between a running
// engine stage and whoever watches it (a CLI, an HTTP worker, a progress bar
// fed by server-sent events).
#include <atomic>
#include <mutex>
#include <string>

namespace voxd {

// What a host embedding the engine implements to watch and stop it (as
// OpenVDB's interrupters do), given to a JobControl with set_host. Both are
// called from the engine's threads, several at once: keep them cheap and
// thread-safe.
class HostInterrupter {
 public:
  virtual ~HostInterrupter() = default;
  // True to stop: the engine then throws Error(cancelled) within ~50 ms.
  virtual bool interrupted() = 0;
  // The whole job's progress rose to `fraction` (0..1, never going back).
  virtual void progressed(double fraction) { (void)fraction; }
};

class JobControl {
 public:
  JobControl() = default;
  // A control that also asks `host` whether to stop and tells it the progress.
  explicit JobControl(HostInterrupter* host) : host_(host) {}
  void set_host(HostInterrupter* host) { host_ = host; }

  void request_cancel() { cancel_.store(true, std::memory_order_relaxed); }
  bool cancel_requested() const {
    if (cancel_.load(std::memory_order_relaxed)) return true;
    return host_ && host_->interrupted();
  }
  // Throws Error(cancelled) if cancellation was requested. Engines call this
  // between units of work small enough that cancel is prompt (< ~50 ms).
  void check_cancelled() const;

  // `fraction` of the current span (the whole job unless set_span narrowed
  // it), so stages that each report 0..1 add up to one steady progress bar.
  // The progress a watcher sees never goes back: a report below what was
  // already reported is not shown (threads finishing chunks out of order),
  // and the largest such step back is kept, for the tests that hold every
  // stage to its share of the bar.
  void set_progress(double fraction) {
    const double b = span_begin_.load(std::memory_order_relaxed), e = span_end_.load(std::memory_order_relaxed);
    const double value = b + (e - b) * fraction;
    double seen = progress_.load(std::memory_order_relaxed);
    while (value > seen && !progress_.compare_exchange_weak(seen, value, std::memory_order_relaxed)) {
    }
    if (value > seen && host_) host_->progressed(value);
    if (value < seen) {
      double back = largest_step_back_.load(std::memory_order_relaxed);
      while (seen - value > back &&
             !largest_step_back_.compare_exchange_weak(back, seen - value, std::memory_order_relaxed)) {
      }
    }
  }
  double progress() const { return progress_.load(std::memory_order_relaxed); }
  // The largest report that fell below the progress already shown (0: the
  // reports only ever rose).
  double largest_step_back() const { return largest_step_back_.load(std::memory_order_relaxed); }
  // Maps the following set_progress calls onto [begin, end] of the job.
  void set_span(double begin, double end) {
    span_begin_.store(begin, std::memory_order_relaxed);
    span_end_.store(end, std::memory_order_relaxed);
  }
  double span_begin() const { return span_begin_.load(std::memory_order_relaxed); }
  double span_end() const { return span_end_.load(std::memory_order_relaxed); }

  // What the job is doing now, in a word or two a person reads beside the
  // progress bar ("voxelize", "analysis: radiography z"); set by whoever
  // runs the stages.
  void set_stage(std::string stage) {
    std::lock_guard lock(stage_mutex_);
    stage_ = std::move(stage);
  }
  std::string stage() const {
    std::lock_guard lock(stage_mutex_);
    return stage_;
  }

 private:
  HostInterrupter* host_ = nullptr;
  std::atomic<bool> cancel_{false};
  std::atomic<double> progress_{0.0};
  std::atomic<double> largest_step_back_{0.0};
  std::atomic<double> span_begin_{0.0}, span_end_{1.0};
  mutable std::mutex stage_mutex_;
  std::string stage_;
};

// Narrows a control's span to [from, to] of its current span for as long as
// it lives (a stage run inside another reports 0..1 of its own share), and
// puts the span back when it goes. A null control is left alone.
class NestedSpan {
 public:
  NestedSpan(JobControl* control, double from, double to)
      : control_(control),
        begin_(control ? control->span_begin() : 0.0),
        end_(control ? control->span_end() : 1.0) {
    if (control_) control_->set_span(begin_ + (end_ - begin_) * from, begin_ + (end_ - begin_) * to);
  }
  ~NestedSpan() {
    if (control_) control_->set_span(begin_, end_);
  }
  NestedSpan(const NestedSpan&) = delete;
  NestedSpan& operator=(const NestedSpan&) = delete;

 private:
  JobControl* control_;
  double begin_, end_;
};

}  // namespace voxd
