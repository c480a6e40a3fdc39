// What a parallel loop costs beyond its pieces (issue #39): the time from
// calling parallel_for (or the ordered pipeline) to its return when the
// pieces do next to nothing, on 2 to 16 threads (1: the pieces alone, one
// after another). The schedule simulation (bench/schedule_simulation.h)
// does not see this cost, and a stage makes from a few loops (mass
// properties) to a few dozen (wall thickness, thickness regions) a run:
// where a loop's pieces take a few hundred microseconds in all, starting
// its threads can cost as much again.
//   loop_overhead_bench --benchmark_filter='threads:(1|2|16)/'
//
// BM_LoopOfEmptyPieces: one piece a thread, each adding to a counter.
// BM_LoopOfShortPieces: 16 pieces a thread of about 4 microseconds of
// arithmetic each, so the threads must really share them (a real stage's
// smallest loops). BM_OrderedPipeline: 4 pieces a thread through the
// ordered pipeline, produced on any thread and consumed in order.
// On a machine with fewer cores than threads the figures include the
// kernel switching between them; compare builds within one run.
#include <benchmark/benchmark.h>

#include <atomic>
#include <cstdint>

#include "encode/ordered_pipeline.h"
#include "voxd/parallel.h"

namespace {

// About 4 microseconds of dependent arithmetic that the compiler cannot drop.
std::uint64_t spin(std::uint64_t seed) {
  std::uint64_t x = seed | 1;
  for (int i = 0; i < 4000; ++i) x = x * 6364136223846793005ull + 1442695040888963407ull;
  return x;
}

// The time an iteration is a loop's, from call to return.
void report(benchmark::State& state) { state.counters["threads"] = static_cast<double>(state.range(0)); }

void BM_LoopOfEmptyPieces(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  std::atomic<std::int64_t> sum{0};
  for (auto _ : state)
    voxd::parallel_for(0, threads, 1, threads,
                       [&](std::int64_t a, std::int64_t) { sum.fetch_add(a, std::memory_order_relaxed); });
  benchmark::DoNotOptimize(sum.load());
  report(state);
}

void BM_LoopOfShortPieces(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  std::atomic<std::uint64_t> sum{0};
  for (auto _ : state)
    voxd::parallel_for(0, 16 * threads, 1, threads, [&](std::int64_t a, std::int64_t) {
      sum.fetch_add(spin(static_cast<std::uint64_t>(a)), std::memory_order_relaxed);
    });
  benchmark::DoNotOptimize(sum.load());
  report(state);
}

void BM_OrderedPipeline(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  std::atomic<std::int64_t> sum{0};
  for (auto _ : state)
    voxd::encode::run_ordered_pipeline(
        4 * threads, threads, static_cast<std::size_t>(2 * threads),
        [&](std::int64_t i, std::size_t) { sum.fetch_add(i, std::memory_order_relaxed); },
        [&](std::int64_t i, std::size_t) { sum.fetch_add(i, std::memory_order_relaxed); });
  benchmark::DoNotOptimize(sum.load());
  report(state);
}

void threads(benchmark::internal::Benchmark* b) {
  for (int t : {1, 2, 4, 8, 16}) b->ArgName("threads")->Arg(t);
  b->UseRealTime();
}

BENCHMARK(BM_LoopOfEmptyPieces)->Apply(threads);
BENCHMARK(BM_LoopOfShortPieces)->Apply(threads);
BENCHMARK(BM_OrderedPipeline)->Apply(threads);

}  // namespace
