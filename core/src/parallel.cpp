#include "voxd/parallel.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

#include "worker_pool.h"

namespace voxd {

int default_thread_count() {
  if (const detail::ScheduleObserver* o = detail::schedule_observer()) return o->cores();
  const unsigned n = std::thread::hardware_concurrency();
  return n == 0 ? 1 : static_cast<int>(n);
}

namespace detail {
namespace {

thread_local bool inside_parallel_work = false;

template <class Body, class A, class B>
[[gnu::noinline]] void parallel_work(const Body& body, A a, B b) {
  inside_parallel_work = true;
  struct Leave {
    ~Leave() { inside_parallel_work = false; }
  } leave;
  body(a, b);
}

template <class Body, class A, class B>
void run_piece(const Body& body, A a, B b) {
  if (inside_parallel_work)
    body(a, b);
  else
    parallel_work(body, a, b);
}

std::atomic<ScheduleObserver*> observer{nullptr};

}  // namespace

void set_schedule_observer(ScheduleObserver* o) noexcept { observer.store(o); }
ScheduleObserver* schedule_observer() noexcept { return observer.load(std::memory_order_relaxed); }
bool inside_parallel_piece() noexcept { return inside_parallel_work; }

void run_parallel_piece(const std::function<void(std::int64_t, std::int64_t)>& body, std::int64_t a,
                        std::int64_t b) {
  run_piece(body, a, b);
}

void run_parallel_piece(const std::function<void(std::int64_t, std::size_t)>& body, std::int64_t a,
                        std::size_t b) {
  run_piece(body, a, b);
}

}  // namespace detail

void parallel_for(std::int64_t begin, std::int64_t end, std::int64_t grain, int threads,
                  const std::function<void(std::int64_t, std::int64_t)>& body) {
  if (end <= begin) return;
  grain = std::max<std::int64_t>(grain, 1);
  const std::int64_t chunks = (end - begin + grain - 1) / grain;
  int n = threads > 0 ? threads : default_thread_count();
  n = static_cast<int>(std::min<std::int64_t>(n, chunks));
  detail::ScheduleObserver* const observer = detail::schedule_observer();
  if (n <= 1 || (observer && detail::inside_parallel_piece())) {
    for (std::int64_t b = begin; b < end; b += grain) body(b, std::min(end, b + grain));
    return;
  }
  if (observer) {  // a benchmark's simulation: each piece timed, one after another
    std::vector<double> seconds;
    seconds.reserve(static_cast<std::size_t>(chunks));
    for (std::int64_t b = begin; b < end; b += grain) {
      const auto start = std::chrono::steady_clock::now();
      detail::run_parallel_piece(body, b, std::min(end, b + grain));
      seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
    observer->loop(n, seconds);
    return;
  }
  std::atomic<std::int64_t> next{0};
  std::atomic<bool> failed{false};
  std::exception_ptr error;
  std::mutex error_mutex;
  const std::function<void()> worker = [&] {
    while (!failed.load(std::memory_order_relaxed)) {
      const std::int64_t c = next.fetch_add(1, std::memory_order_relaxed);
      if (c >= chunks) return;
      const std::int64_t b = begin + c * grain;
      try {
        detail::run_parallel_piece(body, b, std::min(end, b + grain));
      } catch (...) {
        std::lock_guard lock(error_mutex);
        if (!error) error = std::current_exception();
        failed.store(true);
      }
    }
  };
  {
    // n - 1 kept threads and this one claim the pieces; the helpers are
    // waited for before the loop's state goes.
    const detail::WorkerHelpers helpers(n - 1, worker);
    worker();
  }
  if (error) std::rethrow_exception(error);
}

}  // namespace voxd
