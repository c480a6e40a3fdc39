#pragma once
// The arithmetic of bench/schedule_simulation.h, apart from the benchmark
// library so that a test can hold it to hand-worked schedules: when pieces
// of measured seconds would be done on a number of threads.
#include <algorithm>
#include <cstddef>
#include <functional>
#include <queue>
#include <span>
#include <vector>

namespace voxd::bench {

// When `threads` threads, each taking the next piece when it is free, are
// done with `pieces` (seconds each, in claim order); `ends` gets each
// piece's end.
inline double list_schedule(int threads, std::span<const double> pieces, std::vector<double>* ends = nullptr) {
  std::priority_queue<double, std::vector<double>, std::greater<>> free_at;
  for (int t = 0; t < std::max(threads, 1); ++t) free_at.push(0.0);
  double last = 0;
  for (const double seconds : pieces) {
    const double end = free_at.top() + seconds;
    free_at.pop();
    free_at.push(end);
    last = std::max(last, end);
    if (ends) ends->push_back(end);
  }
  return last;
}

// When an ordered pipeline (encode::run_ordered_pipeline) would have
// consumed its last piece: piece i produced by whichever of `threads`
// threads is free first, but not before piece i - slots was consumed (its
// slot is free then), and consumed in order on a lane of its own once it is
// produced and the piece before it consumed. Slightly optimistic: the real
// consumer is one of the threads.
inline double pipeline_schedule(int threads, std::size_t slots, std::span<const double> produce,
                                std::span<const double> consume) {
  std::priority_queue<double, std::vector<double>, std::greater<>> free_at;
  for (int t = 0; t < std::max(threads, 1); ++t) free_at.push(0.0);
  const std::size_t window = std::max<std::size_t>(slots, 1);
  std::vector<double> consumed(produce.size());
  double last = 0;
  for (std::size_t i = 0; i < produce.size(); ++i) {
    const double slot_free = i >= window ? consumed[i - window] : 0.0;
    const double produced = std::max(free_at.top(), slot_free) + produce[i];
    free_at.pop();
    free_at.push(produced);
    last = consumed[i] = std::max(last, produced) + consume[i];
  }
  return last;
}

}  // namespace voxd::bench
