#pragma once
// How long a benchmark's section would take on more threads than the
// machine has cores, from the pieces its loops are cut into (issue #39).
// Amdahl's bound from serial instructions (bench/serial_fraction.sh) takes
// every loop as divisible without end; a loop of 20 equal pieces on 16
// threads takes two pieces' time, not 20/16 of one, and one long piece
// holds back the rest. This simulation sees that.
//
// With VOXD_SCHEDULE_SIMULATION set, each outermost parallel_for and
// ordered pipeline of the section runs its pieces one after another on the
// calling thread, timing each (voxd::detail::ScheduleObserver), loops that
// ask for every core, or cut themselves by the cores, see the simulated
// machine's (the benchmark's thread count), and the section's time on the
// loops' thread counts is worked out:
//   - a loop: its pieces in the order they would be claimed, each taken by
//     whichever thread is free first (parallel_for's dynamic claiming);
//   - a pipeline: pieces produced as in a loop, none before the piece that
//     last held its slot is consumed, consumed in order on a lane of its
//     own (slightly optimistic: the real consumer is one of the threads);
//   - everything outside loops: serial, as measured.
// Left out, so the figure is a bound: starting and joining threads, and
// threads slowing each other down (memory bandwidth, caches, turbo
// clocks). Counters: simulated_ms (the section on the loops' threads),
// serial_ms (outside any loop), pieces_in_loops. VOXD_SCHEDULE_SIMULATION=loops
// also prints each loop to stderr (threads, pieces, their sum, the
// simulated time, the longest piece, the serial time since the loop before),
// to find the loop, or the gap between loops, that holds a stage back.
//   VOXD_SCHEDULE_SIMULATION=1 build/bench/analysis_stages_bench --benchmark_filter=...
// bench/schedule_bound.sh pairs a section's 2- and 16-thread figures.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <span>
#include <thread>
#include <vector>

#include "schedule_model.h"
#include "voxd/parallel.h"

namespace voxd::bench {

class ScheduleSimulation final : public detail::ScheduleObserver {
 public:
  // `cores`: the machine simulated, what loops asked for every core get
  // (and what cuts loops by the machine's size); 0: this machine's.
  ScheduleSimulation(benchmark::State& state, int cores)
      : state_(state),
        cores_(cores > 0 ? cores : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()))),
        on_(std::getenv("VOXD_SCHEDULE_SIMULATION") != nullptr),
        print_(on_ && std::strcmp(std::getenv("VOXD_SCHEDULE_SIMULATION"), "loops") == 0) {
    if (!on_) return;
    detail::set_schedule_observer(this);
    start_ = last_report_ = std::chrono::steady_clock::now();
  }
  ~ScheduleSimulation() override {
    if (!on_) return;
    detail::set_schedule_observer(nullptr);
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    const double iterations = state_.iterations() > 0 ? static_cast<double>(state_.iterations()) : 1.0;
    const double serial = std::max(0.0, wall - in_loops_);
    state_.counters["serial_ms"] = 1e3 * serial / iterations;
    state_.counters["simulated_ms"] = 1e3 * (serial + simulated_) / iterations;
    state_.counters["pieces_in_loops"] = static_cast<double>(pieces_) / iterations;
  }
  ScheduleSimulation(const ScheduleSimulation&) = delete;
  ScheduleSimulation& operator=(const ScheduleSimulation&) = delete;

  int cores() const override { return cores_; }

  void loop(int threads, std::span<const double> pieces) override {
    double sum = 0, longest = 0;
    for (const double s : pieces) {
      sum += s;
      longest = std::max(longest, s);
    }
    const double simulated = list_schedule(threads, pieces);
    in_loops_ += sum;
    simulated_ += simulated;
    pieces_ += pieces.size();
    if (print_)
      std::fprintf(stderr,
                   "loop: %2d threads %6zu pieces %9.3f ms in all -> %8.3f ms, longest piece %8.3f ms; "
                   "serial before it %8.3f ms\n",
                   threads, pieces.size(), 1e3 * sum, 1e3 * simulated, 1e3 * longest, 1e3 * serial_since_last(sum));
  }

  void pipeline(int threads, std::size_t slots, std::span<const double> produce,
                std::span<const double> consume) override {
    const double consumed = pipeline_schedule(threads, slots, produce, consume);
    for (std::size_t i = 0; i < produce.size(); ++i) in_loops_ += produce[i] + consume[i];
    simulated_ += consumed;
    pieces_ += produce.size();
    if (print_) {
      double made = 0, used = 0, longest = 0;
      for (std::size_t i = 0; i < produce.size(); ++i) {
        made += produce[i];
        used += consume[i];
        longest = std::max(longest, produce[i]);
      }
      std::fprintf(stderr,
                   "pipeline: %2d threads %4zu slots %6zu pieces %9.3f ms made + %8.3f ms consumed in all -> "
                   "%8.3f ms, longest piece %8.3f ms; serial before it %8.3f ms\n",
                   threads, slots, produce.size(), 1e3 * made, 1e3 * used, 1e3 * consumed, 1e3 * longest,
                   1e3 * serial_since_last(made + used));
    }
  }

 private:
  // Seconds on the calling thread, outside loops, since the last loop
  // reported (or the section's start), this one's `in_loop` seconds aside.
  double serial_since_last(double in_loop) {
    const auto now = std::chrono::steady_clock::now();
    const double gap = std::chrono::duration<double>(now - last_report_).count() - in_loop;
    last_report_ = now;
    return std::max(0.0, gap);
  }

  benchmark::State& state_;
  const int cores_;
  const bool on_;
  const bool print_;
  std::chrono::steady_clock::time_point start_, last_report_;
  double in_loops_ = 0;   // seconds the loops' pieces took, one after another
  double simulated_ = 0;  // seconds they would take on their threads
  std::size_t pieces_ = 0;
};

}  // namespace voxd::bench
