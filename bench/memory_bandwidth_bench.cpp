// The machine's own memory bandwidth on 1 to 16 threads, through the same
// parallel_for the stages use (issue #39): the ceiling a stage that streams
// its voxels through memory can reach. A stage whose speed-up from 2 to 16
// threads stops near this one's is bound by memory, not by serial work
// (which bench/serial_fraction.sh counts); one far below it is not. And
// how fast a fresh gigabyte of volume memory is faulted in on 1 to 16
// threads.
// bench/gpu/check.sh scaling runs it on the lent 16-core machines.
//   memory_bandwidth_bench --benchmark_filter='threads:(2|16)/'
//
// Three loops over 1 GiB arrays of 64-bit words, STREAM's kernels without
// the arithmetic: read (a sum), write (a fill) and copy, in pieces of 1 MiB
// claimed by the threads as a stage's rows are. The arrays are first
// written by the same pieces on all threads, so their pages lie where a
// stage's own would (first touch, on a machine with several memory nodes).
#include <benchmark/benchmark.h>

#include <cstdint>
#include <cstring>
#include <vector>

#include "voxd/parallel.h"
#include "voxd/uncleared_vector.h"
#include "voxd/volume_memory.h"

namespace {

constexpr std::int64_t kWords = std::int64_t{1} << 27;  // 1 GiB of 64-bit words
constexpr std::int64_t kPiece = std::int64_t{1} << 17;  // 1 MiB

using Words = voxd::UnclearedVector<std::uint64_t>;

Words& array(int which) {
  static Words arrays[2] = {Words(kWords), Words(kWords)};
  static const bool touched = [] {
    for (Words& a : arrays)
      voxd::parallel_for(0, kWords, kPiece, 0, [&](std::int64_t b, std::int64_t e) {
        for (std::int64_t i = b; i < e; ++i) a[static_cast<std::size_t>(i)] = static_cast<std::uint64_t>(i);
      });
    return true;
  }();
  (void)touched;
  return arrays[which];
}

void report(benchmark::State& state, std::int64_t bytes_a_pass) {
  state.SetBytesProcessed(state.iterations() * bytes_a_pass);
  state.counters["threads"] = static_cast<double>(state.range(0));
}

void BM_MemoryRead(benchmark::State& state) {
  const Words& a = array(0);
  const int threads = static_cast<int>(state.range(0));
  std::vector<std::uint64_t> sums(static_cast<std::size_t>(kWords / kPiece));
  for (auto _ : state) {
    voxd::parallel_for(0, kWords, kPiece, threads, [&](std::int64_t b, std::int64_t e) {
      std::uint64_t sum = 0;
      for (std::int64_t i = b; i < e; ++i) sum += a[static_cast<std::size_t>(i)];
      sums[static_cast<std::size_t>(b / kPiece)] = sum;
    });
    benchmark::DoNotOptimize(sums.data());
  }
  report(state, kWords * 8);
}

void BM_MemoryWrite(benchmark::State& state) {
  Words& a = array(0);
  const int threads = static_cast<int>(state.range(0));
  std::uint64_t value = 0;
  for (auto _ : state) {
    ++value;
    voxd::parallel_for(0, kWords, kPiece, threads, [&](std::int64_t b, std::int64_t e) {
      for (std::int64_t i = b; i < e; ++i) a[static_cast<std::size_t>(i)] = value;
    });
    benchmark::DoNotOptimize(a.data());
    benchmark::ClobberMemory();
  }
  report(state, kWords * 8);
}

void BM_MemoryCopy(benchmark::State& state) {
  const Words& from = array(0);
  Words& to = array(1);
  const int threads = static_cast<int>(state.range(0));
  for (auto _ : state) {
    voxd::parallel_for(0, kWords, kPiece, threads, [&](std::int64_t b, std::int64_t e) {
      std::memcpy(to.data() + b, from.data() + b, static_cast<std::size_t>(e - b) * 8);
    });
    benchmark::DoNotOptimize(to.data());
    benchmark::ClobberMemory();
  }
  report(state, kWords * 16);  // read and written
}

// A fresh volume's pages faulted in by the threads that first write them,
// as every stage's new volumes are (voxd/volume_memory.h: huge pages where
// the kernel allows): how far the kernel's page faults scale is a ceiling
// too.
// The first gigabyte is faulted in once, untimed: on a VM whose host backs
// its memory lazily the very first touch costs the host's faults too
// (docs/benchmarks.md, 2026-11-29), which no later request pays.
void fault_in_volume(int threads) {
  constexpr std::size_t kBytes = std::size_t{1} << 30;
  auto* p = static_cast<std::uint8_t*>(voxd::allocate_volume_memory(kBytes, true));
  voxd::parallel_for(0, static_cast<std::int64_t>(kBytes), std::int64_t{1} << 21, threads,
                     [&](std::int64_t b, std::int64_t e) {
                       for (std::int64_t i = b; i < e; i += 4096) p[i] = 1;
                     });
  benchmark::DoNotOptimize(p);
  voxd::free_volume_memory(p, kBytes);
}

void BM_MemoryFaultIn(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  static const bool warm = (fault_in_volume(0), true);
  (void)warm;
  for (auto _ : state) fault_in_volume(threads);
  report(state, std::int64_t{1} << 30);
}

void threads(benchmark::internal::Benchmark* b) {
  for (int t : {1, 2, 4, 8, 16}) b->ArgName("threads")->Arg(t);
  b->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(0.3);
}

BENCHMARK(BM_MemoryRead)->Apply(threads);
BENCHMARK(BM_MemoryWrite)->Apply(threads);
BENCHMARK(BM_MemoryCopy)->Apply(threads);
BENCHMARK(BM_MemoryFaultIn)->Apply(threads);

}  // namespace
