#pragma once
// Minimal fork-join parallel loop over an index range, split into contiguous
// chunks claimed dynamically, so uneven work (dense vs empty slabs) balances.
#include <cstddef>
#include <cstdint>
#include <functional>

namespace voxd {

// Number of worker threads to use when a caller passes 0: hardware concurrency.
int default_thread_count();

// Calls body(chunk_begin, chunk_end) for consecutive chunks of [begin, end) of
// at most `grain` indices, on up to `threads` threads (0 = default). The first
// exception thrown by a body is rethrown on the calling thread after all
// threads stop claiming chunks.
void parallel_for(std::int64_t begin, std::int64_t end, std::int64_t grain, int threads,
                  const std::function<void(std::int64_t, std::int64_t)>& body);

namespace detail {
// Runs one piece of the work that parallel_for and encode::run_ordered_pipeline
// hand to threads. The outermost piece on each thread runs inside
// `parallel_work` (parallel.cpp), out of line and never inlined, so a profile
// tells parallel work from serial: the instructions outside it are what
// Amdahl's law calls the serial part (bench/serial_fraction.sh). A piece of a
// parallel_for nested in a piece on the same thread is inside it already, so
// none is counted twice.
void run_parallel_piece(const std::function<void(std::int64_t, std::int64_t)>& body, std::int64_t a,
                        std::int64_t b);
void run_parallel_piece(const std::function<void(std::int64_t, std::size_t)>& body, std::int64_t a,
                        std::size_t b);
}  // namespace detail

}  // namespace voxd
