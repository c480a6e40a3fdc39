// The schedule simulation's arithmetic (bench/schedule_model.h) against
// schedules worked out by hand: the bound it gives for 16 cores is only as
// good as this.
#include "schedule_model.h"

#include <gtest/gtest.h>

#include <vector>

namespace voxd::bench {
namespace {

TEST(ListSchedule, GivesEachPieceToTheThreadFreeFirst) {
  // Two threads: 3 | 1, then 1 goes to the second (free at 1), then 2 to the
  // second again (free at 2): ends 3, 1, 2, 4.
  const std::vector<double> pieces{3, 1, 1, 2};
  std::vector<double> ends;
  EXPECT_DOUBLE_EQ(list_schedule(2, pieces, &ends), 4.0);
  EXPECT_EQ(ends, (std::vector<double>{3, 1, 2, 4}));
  // One thread: the sum; more threads than pieces: the longest.
  EXPECT_DOUBLE_EQ(list_schedule(1, pieces), 7.0);
  EXPECT_DOUBLE_EQ(list_schedule(16, pieces), 3.0);
  // 20 equal pieces on 16 threads take two pieces' time, not 20/16 of one.
  EXPECT_DOUBLE_EQ(list_schedule(16, std::vector<double>(20, 1.0)), 2.0);
}

TEST(PipelineSchedule, ConsumesInOrderOnALaneOfItsOwn) {
  // Produced at 3, 1, 2, 3 on two threads (slots enough for all); consumed
  // from 3 on, half a second each, in order: 3.5, 4, 4.5, 5.
  const std::vector<double> produce{3, 1, 1, 1}, consume(4, 0.5);
  EXPECT_DOUBLE_EQ(pipeline_schedule(2, 4, produce, consume), 5.0);
}

TEST(PipelineSchedule, WaitsForASlotHeldByAPieceNotYetConsumed) {
  const std::vector<double> produce{3, 1, 1, 1}, consume(4, 0.0);
  // Four slots: piece 0 is the longest, the others done on the second thread
  // by 3; all consumed at 3.
  EXPECT_DOUBLE_EQ(pipeline_schedule(2, 4, produce, consume), 3.0);
  // Two slots: piece 2 takes piece 0's slot, free once it is consumed at 3,
  // so the second thread idles from 1 to 3; pieces 2 and 3 end at 4.
  EXPECT_DOUBLE_EQ(pipeline_schedule(2, 2, produce, consume), 4.0);
  // One slot: strictly one piece after another.
  EXPECT_DOUBLE_EQ(pipeline_schedule(2, 1, produce, consume), 6.0);
}

}  // namespace
}  // namespace voxd::bench
