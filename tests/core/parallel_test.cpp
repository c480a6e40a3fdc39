// parallel_for and the ordered pipeline: every index once, on threads kept
// from loop to loop, and what a benchmark's schedule observer
// (bench/schedule_simulation.h) is told.
#include "voxd/parallel.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <tuple>
#include <utility>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

#include <condition_variable>
#include <set>

#include "encode/ordered_pipeline.h"
#include "worker_pool.h"

namespace voxd {
namespace {

TEST(ParallelFor, CoversEveryIndexOnceInPiecesOfTheGrain) {
  for (int threads : {1, 3, 8}) {
    std::vector<std::atomic<int>> hits(1000);
    std::atomic<int> oversized{0};
    parallel_for(5, 1000, 7, threads, [&](std::int64_t a, std::int64_t b) {
      if (b - a > 7 || (a - 5) % 7 != 0) ++oversized;
      for (std::int64_t i = a; i < b; ++i) ++hits[static_cast<std::size_t>(i)];
    });
    EXPECT_EQ(oversized.load(), 0) << threads;
    for (std::size_t i = 0; i < hits.size(); ++i) ASSERT_EQ(hits[i].load(), i < 5 ? 0 : 1) << i << " " << threads;
  }
}

TEST(ParallelFor, RethrowsABodysErrorOnTheCallingThread) {
  EXPECT_THROW(parallel_for(0, 100, 1, 4,
                            [](std::int64_t a, std::int64_t) {
                              if (a == 37) throw std::runtime_error("piece 37");
                            }),
               std::runtime_error);
}

// Every piece of a loop on `threads` threads waits until `threads` pieces
// have begun (for at most `timeout`): whether they all did, so the loop's
// threads ran at once, as many as asked for. `ids` receives the kernel's
// ids of the threads that ran them. No gtest assertions: a forked child
// calls it too.
bool began_at_once(int threads, std::chrono::seconds timeout, std::set<pid_t>& ids) {
  std::mutex mutex;
  std::condition_variable all_began;
  int began = 0;
  bool at_once = true;
  parallel_for(0, threads, 1, threads, [&](std::int64_t, std::int64_t) {
    std::unique_lock lock(mutex);
    ids.insert(::gettid());
    if (++began == threads) all_began.notify_all();
    if (!all_began.wait_for(lock, timeout, [&] { return began == threads; })) at_once = false;
  });
  return at_once;
}

// The same within 20 s, as a test's expectation; returns the threads' ids.
std::set<pid_t> threads_running_at_once(int threads) {
  std::set<pid_t> ids;
  EXPECT_TRUE(began_at_once(threads, std::chrono::seconds(20), ids)) << "not all " << threads << " pieces began";
  return ids;
}

TEST(ParallelFor, RunsOnAsManyThreadsAsAskedKeptFromLoopToLoop) {
  const std::set<pid_t> first = threads_running_at_once(6);
  ASSERT_EQ(first.size(), 6u);
  EXPECT_TRUE(first.count(::gettid()));  // the caller takes its share
  const int kept = detail::kept_worker_threads();
  EXPECT_GE(kept, 5);
  for (int round = 0; round < 20; ++round) {
    // The same helpers again (kernel ids are not reused this soon), none started anew.
    const std::set<pid_t> again = threads_running_at_once(6);
    ASSERT_EQ(again, first) << "round " << round;
  }
  EXPECT_EQ(detail::kept_worker_threads(), kept);
  // More at once than kept: more are started, and kept.
  EXPECT_EQ(threads_running_at_once(kept + 3).size(), static_cast<std::size_t>(kept + 3));
  EXPECT_EQ(detail::kept_worker_threads(), kept + 2);
}

TEST(ParallelFor, AChildOfForkStartsThreadsOfItsOwn) {
  // The parent keeps helpers; a forked child has none of them (a host
  // embedding the engine may fork), so its loops must start their own.
  ASSERT_EQ(threads_running_at_once(4).size(), 4u);
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    // The child only answers with its exit status.
    std::set<pid_t> ids;
    const bool at_once = began_at_once(4, std::chrono::seconds(5), ids);
    ::_exit(at_once ? 0 : 1);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "the child's loop did not run on 4 threads at once";
  EXPECT_EQ(threads_running_at_once(4).size(), 4u);  // the parent's helpers serve on
}

TEST(ParallelFor, NestedAndConcurrentLoopsCoverEveryIndexOnce) {
  // Loops within loops, from several threads of the caller's own at once:
  // the pool hands out and takes back helpers while others run.
  constexpr int kCallers = 4, kRounds = 50, kOuter = 12, kInner = 40;
  std::vector<std::atomic<int>> hits(static_cast<std::size_t>(kCallers * kOuter * kInner));
  std::vector<std::thread> callers;
  for (int c = 0; c < kCallers; ++c)
    callers.emplace_back([&, c] {
      for (int round = 0; round < kRounds; ++round)
        parallel_for(0, kOuter, 1, 3, [&](std::int64_t a, std::int64_t) {
          parallel_for(0, kInner, 3, 1 + round % 4, [&](std::int64_t b, std::int64_t e) {
            for (std::int64_t i = b; i < e; ++i) ++hits[static_cast<std::size_t>((c * kOuter + a) * kInner + i)];
          });
        });
    });
  for (auto& t : callers) t.join();
  for (std::size_t i = 0; i < hits.size(); ++i) ASSERT_EQ(hits[i].load(), kRounds) << i;
}

TEST(WorkerHelpers, TakeBackTheWorkFromThoseNotYetAwake) {
  // The caller waits at once: helpers that woke in time ran the work once,
  // the others never do (not even later), and all of them serve the next
  // loop.
  constexpr int kRounds = 200;
  std::vector<std::atomic<int>> ran(kRounds);
  std::vector<int> seen(kRounds);
  for (int round = 0; round < kRounds; ++round) {
    std::atomic<int>& count = ran[static_cast<std::size_t>(round)];
    const std::function<void()> work = [&count] { ++count; };
    detail::WorkerHelpers helpers(3, work);
    EXPECT_EQ(helpers.handed(), 3);
    helpers.wait();
    seen[static_cast<std::size_t>(round)] = count.load();
    EXPECT_LE(count.load(), 3);
    helpers.wait();  // again: at once
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  for (int round = 0; round < kRounds; ++round)
    ASSERT_EQ(ran[static_cast<std::size_t>(round)].load(), seen[static_cast<std::size_t>(round)]) << round;
  EXPECT_EQ(threads_running_at_once(4).size(), 4u);
}

// Records what it is told, and on which thread each piece ran.
class RecordingObserver final : public detail::ScheduleObserver {
 public:
  struct Loop {
    int threads;
    std::size_t pieces;
    std::size_t consumed;  // a pipeline's consume steps; 0 for a loop
    std::size_t slots;     // a pipeline's; 0 for a loop
  };
  std::vector<Loop> loops;
  int cores() const override { return 5; }
  void loop(int threads, std::span<const double> pieces) override {
    for (double s : pieces) EXPECT_GE(s, 0.0);
    loops.push_back({threads, pieces.size(), 0, 0});
  }
  void pipeline(int threads, std::size_t slots, std::span<const double> produce,
                std::span<const double> consume) override {
    loops.push_back({threads, produce.size(), consume.size(), slots});
  }
};

struct Observing {
  explicit Observing(detail::ScheduleObserver* o) { detail::set_schedule_observer(o); }
  ~Observing() { detail::set_schedule_observer(nullptr); }
};

TEST(ScheduleObserver, IsToldEachOutermostLoopsPiecesRunInClaimOrderOnTheCallingThread) {
  RecordingObserver observer;
  const auto caller = std::this_thread::get_id();
  std::vector<std::pair<std::int64_t, std::int64_t>> order;
  bool elsewhere = false;
  {
    const Observing observing(&observer);
    parallel_for(0, 100, 7, 4, [&](std::int64_t a, std::int64_t b) {
      elsewhere |= std::this_thread::get_id() != caller;
      order.emplace_back(a, b);
      // Nested: runs inline, as part of this piece, and is not a loop of its own.
      parallel_for(0, 50, 1, 4, [&](std::int64_t, std::int64_t) { elsewhere |= std::this_thread::get_id() != caller; });
    });
    // One thread: serial work, not a loop to simulate.
    parallel_for(0, 100, 7, 1, [](std::int64_t, std::int64_t) {});
    // More threads than pieces: the loop's threads are its pieces.
    parallel_for(0, 3, 1, 16, [](std::int64_t, std::int64_t) {});
    // Every core: the simulated machine's.
    EXPECT_EQ(default_thread_count(), 5);
    parallel_for(0, 100, 1, 0, [](std::int64_t, std::int64_t) {});
  }
  EXPECT_EQ(default_thread_count(), static_cast<int>(std::max(1u, std::thread::hardware_concurrency())));
  EXPECT_FALSE(elsewhere);
  ASSERT_EQ(order.size(), 15u);
  for (std::size_t p = 0; p < order.size(); ++p)
    EXPECT_EQ(order[p], std::make_pair(static_cast<std::int64_t>(7 * p), std::min<std::int64_t>(100, 7 * p + 7)));
  ASSERT_EQ(observer.loops.size(), 3u);
  EXPECT_EQ(observer.loops[2].threads, 5);
  EXPECT_EQ(observer.loops[2].pieces, 100u);
  EXPECT_EQ(observer.loops[0].threads, 4);
  EXPECT_EQ(observer.loops[0].pieces, 15u);
  EXPECT_EQ(observer.loops[1].threads, 3);
  EXPECT_EQ(observer.loops[1].pieces, 3u);

  // Without it, threads again and nothing told.
  std::mutex mutex;
  std::vector<std::thread::id> ids;
  parallel_for(0, 64, 1, 4, [&](std::int64_t, std::int64_t) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
    std::lock_guard lock(mutex);
    ids.push_back(std::this_thread::get_id());
  });
  std::sort(ids.begin(), ids.end());
  EXPECT_GT(std::unique(ids.begin(), ids.end()) - ids.begin(), 1);
  EXPECT_EQ(observer.loops.size(), 3u);
}

TEST(ScheduleObserver, IsToldAPipelinesProducedAndConsumedPiecesInOrder) {
  RecordingObserver observer;
  const auto caller = std::this_thread::get_id();
  using Step = std::tuple<char, std::int64_t, std::size_t>;  // produce or consume, piece, slot
  std::vector<Step> steps;
  bool elsewhere = false;
  {
    const Observing observing(&observer);
    encode::run_ordered_pipeline(
        5, 3, 2,
        [&](std::int64_t i, std::size_t slot) {
          elsewhere |= std::this_thread::get_id() != caller;
          steps.emplace_back('p', i, slot);
        },
        [&](std::int64_t i, std::size_t slot) {
          // A loop within consume is part of its serial time, not a loop of its own.
          parallel_for(0, 10, 1, 4, [](std::int64_t, std::int64_t) {});
          steps.emplace_back('c', i, slot);
        });
  }
  EXPECT_FALSE(elsewhere);
  std::vector<Step> expected;
  for (std::int64_t i = 0; i < 5; ++i) {
    expected.emplace_back('p', i, i % 2);
    expected.emplace_back('c', i, i % 2);
  }
  EXPECT_EQ(steps, expected);
  ASSERT_EQ(observer.loops.size(), 1u);
  EXPECT_EQ(observer.loops[0].threads, 3);
  EXPECT_EQ(observer.loops[0].pieces, 5u);
  EXPECT_EQ(observer.loops[0].consumed, 5u);
  EXPECT_EQ(observer.loops[0].slots, 2u);
}

}  // namespace
}  // namespace voxd
