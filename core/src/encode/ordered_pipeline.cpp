#include "encode/ordered_pipeline.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <vector>

#include "voxd/parallel.h"
#include "worker_pool.h"

namespace voxd::encode {
void run_ordered_pipeline(std::int64_t count, int threads, std::size_t slot_count,
                          const std::function<void(std::int64_t, std::size_t)>& produce,
                          const std::function<void(std::int64_t, std::size_t)>& consume) {
  if (count <= 0) return;
  const int wanted_threads =
      static_cast<int>(std::min<std::int64_t>(threads > 0 ? threads : default_thread_count(), count));
  // Signed, for the `i - slots` comparisons below.
  const auto slots = static_cast<std::int64_t>(std::max<std::size_t>(slot_count, 1));
  if (detail::ScheduleObserver* const observer = detail::schedule_observer()) {
    // A benchmark's simulation: each piece produced and consumed in turn, timed.
    const bool outermost = !detail::inside_parallel_piece() && wanted_threads > 1;
    std::vector<double> produce_seconds, consume_seconds;
    const auto seconds_of = [](auto&& step) {
      const auto start = std::chrono::steady_clock::now();
      step();
      return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    };
    for (std::int64_t i = 0; i < count; ++i) {
      const auto slot = static_cast<std::size_t>(i % slots);
      produce_seconds.push_back(seconds_of([&] {
        if (outermost)
          detail::run_parallel_piece(produce, i, slot);
        else
          produce(i, slot);
      }));
      // A loop within consume is part of its serial time (as if on one thread).
      consume_seconds.push_back(seconds_of([&] {
        if (outermost)
          detail::run_parallel_piece(consume, i, slot);
        else
          consume(i, slot);
      }));
    }
    if (outermost)
      observer->pipeline(wanted_threads, static_cast<std::size_t>(slots), produce_seconds, consume_seconds);
    return;
  }

  std::mutex mutex;
  std::condition_variable changed;
  std::atomic<std::int64_t> next_claim{0};
  // Guarded by mutex:
  std::vector<char> done(static_cast<std::size_t>(slots), 0);  // slot holds a produced, unconsumed piece
  std::int64_t consumed = 0;                                    // pieces [0, consumed) are consumed
  bool failed = false;
  std::exception_ptr error;

  const auto fail = [&](std::exception_ptr e) {
    {
      std::lock_guard lock(mutex);
      if (!error) error = e;
      failed = true;
    }
    changed.notify_all();
  };
  // Produces claimed piece i once its slot is free; false if the pipeline failed.
  const auto produce_claimed = [&](std::int64_t i) {
    const auto slot = static_cast<std::size_t>(i % slots);
    {
      std::unique_lock lock(mutex);
      changed.wait(lock, [&] { return failed || consumed > i - slots; });
      if (failed) return false;
    }
    try {
      // On one thread the pieces are serial work, and a profile should say so.
      if (wanted_threads > 1)
        detail::run_parallel_piece(produce, i, slot);
      else
        produce(i, slot);
    } catch (...) {
      fail(std::current_exception());
      return false;
    }
    {
      std::lock_guard lock(mutex);
      done[slot] = 1;
    }
    changed.notify_all();
    return true;
  };
  const std::function<void()> worker = [&] {
    for (;;) {
      const std::int64_t i = next_claim.fetch_add(1);
      if (i >= count || !produce_claimed(i)) return;
    }
  };

  // The helpers produce; they are waited for on any way out of this
  // function. The loop below catches everything and sets `failed` first,
  // so helpers waiting for a slot wake up and return.
  detail::WorkerHelpers helpers(wanted_threads - 1, worker);

  try {
    for (;;) {
      std::size_t slot = 0;
      {
        std::unique_lock lock(mutex);
        if (failed || consumed == count) break;
        slot = static_cast<std::size_t>(consumed % slots);
        if (!done[slot]) {
          // Rather than idle, produce the next unclaimed piece if its slot is free.
          std::int64_t i = next_claim.load();
          if (i < count && consumed > i - slots && next_claim.compare_exchange_strong(i, i + 1)) {
            lock.unlock();
            produce_claimed(i);
            continue;
          }
          changed.wait(lock, [&] {
            const std::int64_t claim = next_claim.load();
            return failed || done[slot] || (claim < count && consumed > claim - slots);
          });
          continue;
        }
      }
      consume(consumed, slot);  // only this thread changes `consumed`
      {
        std::lock_guard lock(mutex);
        done[slot] = 0;
        ++consumed;
      }
      changed.notify_all();
    }
  } catch (...) {
    fail(std::current_exception());
  }
  helpers.wait();  // after this, `error` is no longer shared
  if (error) std::rethrow_exception(error);
}

}  // namespace voxd::encode
