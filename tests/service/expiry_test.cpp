// When finished jobs expire (server/jobs/expiry.h), apart from the job engine
// that removes them.
#include <atomic>
#include <chrono>
#include <thread>

#include <gtest/gtest.h>

#include "server/jobs/expiry.h"
#include "server/jobs/job_record.h"

namespace voxd::server {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::system_clock;

JobSnapshot job_in(JobState state, Clock::time_point finished_at) {
  JobSnapshot s;
  s.state = state;
  if (finished(state)) s.finished_at = format_time(finished_at);
  return s;
}

TEST(Expiry, AFinishedJobExpiresOnlyOnceItsTtlHasPassed) {
  const auto now = Clock::now();
  for (JobState state : {JobState::succeeded, JobState::failed, JobState::cancelled}) {
    EXPECT_FALSE(expired(job_in(state, now - 50s), now, 60s)) << to_string(state);
    EXPECT_TRUE(expired(job_in(state, now - 70s), now, 60s)) << to_string(state);
  }
}

TEST(Expiry, JobsThatHaveNotFinishedNeverExpire) {
  const auto now = Clock::now();
  EXPECT_FALSE(expired(job_in(JobState::queued, now), now + 1000h, 1s));
  EXPECT_FALSE(expired(job_in(JobState::running, now), now + 1000h, 1s));
}

TEST(Expiry, SweepsEveryTenthOfTheTtlWithinOneSecondAndOneMinute) {
  EXPECT_EQ(ExpiryTimer::period_for(1s), 1s);
  EXPECT_EQ(ExpiryTimer::period_for(100s), 10s);
  EXPECT_EQ(ExpiryTimer::period_for(86400s), 60s);
}

TEST(Expiry, TheTimerSweepsAndStopsWhenDestroyed) {
  std::atomic<int> sweeps{0};
  {
    ExpiryTimer timer(1s, [&] { ++sweeps; });
    for (int i = 0; i < 100 && sweeps == 0; ++i) std::this_thread::sleep_for(50ms);
  }
  ASSERT_GE(sweeps.load(), 1);
  const int after = sweeps.load();
  std::this_thread::sleep_for(1200ms);
  EXPECT_EQ(sweeps.load(), after);  // no sweep once the timer is gone
}

}  // namespace
}  // namespace voxd::server
