#pragma once
// Minimal fork-join parallel loop over an index range, split into contiguous
// chunks claimed dynamically, so uneven work (dense vs empty slabs) balances.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>

namespace voxd {

// Number of worker threads to use when a caller passes 0: hardware concurrency.
int default_thread_count();

// Calls body(chunk_begin, chunk_end) for consecutive chunks of [begin, end) of
// at most `grain` indices, on up to `threads` threads (0 = default): the
// calling thread and threads kept from loop to loop (core/src/worker_pool.h),
// which claim the chunks in order. The first exception thrown by a body is
// rethrown on the calling thread after all threads stop claiming chunks.
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

// What a benchmark sees of the work threads would share, to work out how
// long a stage would take on more cores than the machine has
// (bench/schedule_simulation.h). While an observer is set (for the whole
// process: benchmarks only), each outermost parallel_for and ordered
// pipeline runs its pieces one after another on the calling thread, in the
// order threads would claim them, a loop nested in a piece runs inline, and
// the observer is told the seconds each piece took and how many threads
// would have shared them. default_thread_count() answers the observer's
// cores, so loops cut by the machine's size are cut as on the machine
// simulated.
class ScheduleObserver {
 public:
  virtual ~ScheduleObserver() = default;
  // The cores of the machine simulated: what a thread count of 0 means.
  virtual int cores() const = 0;
  virtual void loop(int threads, std::span<const double> pieces) = 0;
  // An ordered pipeline: piece i is produced on any thread once piece
  // i - slots is consumed (it held the same slot), then consumed in order
  // on one.
  virtual void pipeline(int threads, std::size_t slots, std::span<const double> produce,
                        std::span<const double> consume) = 0;
};
void set_schedule_observer(ScheduleObserver* observer) noexcept;  // nullptr: threads again
ScheduleObserver* schedule_observer() noexcept;                   // the one set, or nullptr
// Whether this thread is running a piece of a loop or pipeline (under an
// observer, a loop nested in it runs inline).
bool inside_parallel_piece() noexcept;

}  // namespace detail

}  // namespace voxd
