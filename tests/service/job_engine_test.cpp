// The service's job engine without HTTP: states, results, persistence,
// cancellation, dedupe, limits.
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <thread>

#include <gtest/gtest.h>

#include "api/param_error.h"
#include "server/jobs/job_manager.h"
#include "support/run_process.h"
#include "support/test_meshes.h"
#include "voxd/error.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd::server {
namespace {

using nlohmann::json;
using namespace std::chrono_literals;

class JobEngineTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = test::make_temp_dir("voxd-jobs"); }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  JobManagerConfig config(int workers = 2, std::size_t queue = 16) const {
    JobManagerConfig c;
    c.workers = workers;
    c.queue_size = queue;
    c.data_dir = dir_;
    return c;
  }
  static JobSnapshot wait_finished(const JobManager& m, const std::string& id, std::chrono::seconds limit = 60s) {
    const auto until = std::chrono::steady_clock::now() + limit;
    for (;;) {
      auto s = m.get(id);
      if (!s) throw std::runtime_error("job vanished");
      if (s->state == JobState::succeeded || s->state == JobState::failed || s->state == JobState::cancelled) return *s;
      if (std::chrono::steady_clock::now() > until) throw std::runtime_error("job did not finish");
      std::this_thread::sleep_for(5ms);
    }
  }
  std::string dir_;
};

std::vector<std::uint8_t> sphere_stl(double r = 1.0, int level = 3) {
  return test::to_binary_stl(test::make_icosphere({0, 0, 0}, r, level));
}

TEST_F(JobEngineTest, JobSucceedsWithTheEnginesVoxelsAndAMeshReport) {
  JobManager m(config());
  const json params = {{"grid", {{"resolution", 40}}}};
  const JobSnapshot s = m.submit(sphere_stl(), "s.stl", params);
  EXPECT_EQ(s.id.size(), 32u);
  EXPECT_EQ(s.mesh_format, "stl_binary");
  EXPECT_EQ(s.grid.dims.x, 40);
  const JobSnapshot done = wait_finished(m, s.id);
  ASSERT_EQ(done.state, JobState::succeeded) << (done.failure ? done.failure->detail : "");
  ASSERT_TRUE(done.mesh.has_value());
  EXPECT_TRUE(done.mesh->watertight);
  EXPECT_DOUBLE_EQ(done.progress, 1.0);
  const auto volume = m.volume(s.id);
  ASSERT_TRUE(volume);
  const BitVolume direct = voxelize(test::make_icosphere({0, 0, 0}, 1.0, 3), done.grid, {});
  EXPECT_EQ(volume->count(), direct.count());
  EXPECT_EQ(*done.filled_voxels, direct.count());
}

TEST_F(JobEngineTest, BadSubmissionsFailAtOnceAndCreateNoJob) {
  JobManager m(config());
  EXPECT_THROW(m.submit(sphere_stl(), "s.stl", json{{"grid", {{"resolution", 0}}}}), api::InvalidParams);
  try {
    m.submit({'n', 'o', 'p', 'e'}, "x.stl", json::object());
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(e.code(), ErrorCode::cancelled);
  }
  try {
    JobManager limited([&] {
      JobManagerConfig c = config();
      c.data_dir = dir_ + "/limited";
      c.limits.max_voxels = 1000;
      return c;
    }());
    limited.submit(sphere_stl(), "s.stl", json{{"grid", {{"resolution", 64}}}});
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::limit_exceeded);
    EXPECT_NE(std::string(e.what()).find("over the limit of 1000"), std::string::npos);
  }
  std::size_t total = 0;
  m.list(0, 10, &total);
  EXPECT_EQ(total, 0u);
}

TEST_F(JobEngineTest, FinishedJobsSurviveARestartAndUnfinishedOnesAreReportedInterrupted) {
  std::string done_id;
  std::uint64_t count = 0;
  {
    JobManager m(config());
    done_id = m.submit(sphere_stl(), "s.stl", json{{"grid", {{"resolution", 32}}}}).id;
    ASSERT_EQ(wait_finished(m, done_id).state, JobState::succeeded);
    count = m.volume(done_id)->count();
  }
  // A record left "running" by a killed process, and a corrupt one.
  const std::string stale = std::string(32, 'a');
  std::filesystem::create_directories(dir_ + "/jobs/" + stale);
  {
    std::ifstream in(dir_ + "/jobs/" + done_id + "/record.json");
    json r = json::parse(in);
    r["id"] = stale;
    r["state"] = "running";
    r["finished_at"] = nullptr;
    std::ofstream(dir_ + "/jobs/" + stale + "/record.json") << r.dump();
  }
  std::filesystem::create_directories(dir_ + "/jobs/" + std::string(32, 'b'));
  std::ofstream(dir_ + "/jobs/" + std::string(32, 'b') + "/record.json") << "{not json";
  JobManager m(config());
  const auto done = m.get(done_id);
  ASSERT_TRUE(done);
  EXPECT_EQ(done->state, JobState::succeeded);
  EXPECT_EQ(m.volume(done_id)->count(), count);
  const auto interrupted = m.get(stale);
  ASSERT_TRUE(interrupted);
  EXPECT_EQ(interrupted->state, JobState::failed);
  ASSERT_TRUE(interrupted->failure);
  EXPECT_EQ(interrupted->failure->type, "interrupted");
  EXPECT_FALSE(m.get(std::string(32, 'b')));  // corrupt record skipped
}

TEST_F(JobEngineTest, RunningJobIsCancelledPromptlyAndFinishedOnesAreDeleted) {
  JobManager m(config(1));
  const auto big = m.submit(sphere_stl(1.0, 5), "s.stl", json{{"grid", {{"resolution", 320}}}, {"inside", "winding"}});
  for (int i = 0; i < 2000 && m.get(big.id)->state != JobState::running; ++i) std::this_thread::sleep_for(1ms);
  ASSERT_EQ(m.get(big.id)->state, JobState::running);
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(m.cancel_or_delete(big.id), JobManager::RemoveResult::cancelled);
  EXPECT_EQ(wait_finished(m, big.id).state, JobState::cancelled);
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 2s);
  EXPECT_EQ(m.cancel_or_delete(big.id), JobManager::RemoveResult::deleted);
  EXPECT_FALSE(m.get(big.id));
  EXPECT_FALSE(std::filesystem::exists(dir_ + "/jobs/" + big.id));
  EXPECT_EQ(m.cancel_or_delete(big.id), JobManager::RemoveResult::not_found);
}

TEST_F(JobEngineTest, FullQueueRefusesWithRetryAfter) {
  JobManager m(config(1, 1));
  const json slow = {{"grid", {{"resolution", 320}}}, {"inside", "winding"}};
  const auto running = m.submit(sphere_stl(1.0, 5), "a.stl", slow);
  for (int i = 0; i < 2000 && m.get(running.id)->state != JobState::running; ++i) std::this_thread::sleep_for(1ms);
  m.submit(sphere_stl(1.0, 4), "b.stl", slow);  // waits in the queue
  try {
    m.submit(sphere_stl(1.0, 3), "c.stl", slow);
    FAIL() << "expected QueueFull";
  } catch (const QueueFull& e) {
    EXPECT_GE(e.retry_after_seconds(), 1);
  }
  EXPECT_EQ(m.counts().queue_depth, 1u);
  m.shutdown(0s);
  EXPECT_THROW(m.submit(sphere_stl(), "d.stl", json::object()), NotAccepting);
}

TEST_F(JobEngineTest, IdenticalSubmissionIsAnsweredFromTheFinishedResult) {
  JobManager m(config());
  const json params = {{"grid", {{"resolution", 24}}}};
  const auto first = m.submit(sphere_stl(), "s.stl", params);
  ASSERT_EQ(wait_finished(m, first.id).state, JobState::succeeded);
  const auto second = m.submit(sphere_stl(), "other-name.stl", params);
  EXPECT_TRUE(second.cached);
  EXPECT_EQ(second.state, JobState::succeeded);
  EXPECT_NE(second.id, first.id);
  EXPECT_EQ(second.content_hash, first.content_hash);
  // Deleting the original leaves the copy's result intact.
  EXPECT_EQ(m.cancel_or_delete(first.id), JobManager::RemoveResult::deleted);
  ASSERT_TRUE(m.volume(second.id));
  EXPECT_EQ(m.volume(second.id)->count(), *second.filled_voxels);
  const auto third = m.submit(sphere_stl(), "s.stl", json{{"grid", {{"resolution", 25}}}});
  EXPECT_FALSE(third.cached);
}

TEST_F(JobEngineTest, SynchronousRunsReturnTheVolumeAndLeaveNoJob) {
  JobManager m(config());
  JobSnapshot s;
  const auto v = m.run_sync(sphere_stl(), "s.stl", json{{"grid", {{"resolution", 30}}}}, &s).solid;
  ASSERT_TRUE(v);
  EXPECT_EQ(s.state, JobState::succeeded);
  EXPECT_EQ(v->count(), *s.filled_voxels);
  std::size_t total = 1;
  m.list(0, 10, &total);
  EXPECT_EQ(total, 0u);
  EXPECT_FALSE(m.get(s.id));
}

TEST_F(JobEngineTest, ConcurrentSubmittersAllSucceedAndStateChangesAreReported) {
  std::mutex seen_mutex;
  std::map<std::string, std::vector<JobState>> seen;
  JobManagerConfig c = config(2, 256);
  c.on_state_change = [&](const JobSnapshot& s) {
    std::lock_guard lock(seen_mutex);
    seen[s.id].push_back(s.state);
  };
  JobManager m(c);
  std::vector<std::thread> threads;
  std::mutex ids_mutex;
  std::vector<std::string> ids;
  for (int t = 0; t < 8; ++t)
    threads.emplace_back([&, t] {
      for (int i = 0; i < 6; ++i) {
        const auto s = m.submit(test::to_binary_stl(test::make_box({0, 0, 0}, {1.0 + t, 2.0, 3.0 + i})), "b.stl",
                                json{{"grid", {{"voxel_size", 0.25}}}});
        std::lock_guard lock(ids_mutex);
        ids.push_back(s.id);
      }
    });
  for (auto& th : threads) th.join();
  for (const auto& id : ids) {
    const auto s = wait_finished(m, id);
    ASSERT_EQ(s.state, JobState::succeeded);
    EXPECT_EQ(*s.filled_voxels, s.grid.voxel_count());  // a box fills its own grid
  }
  std::size_t total = 0;
  const auto page = m.list(5, 10, &total);
  EXPECT_EQ(total, 48u);
  EXPECT_EQ(page.size(), 10u);
  EXPECT_GE(page.front().created_at, page.back().created_at);
  m.shutdown(5s);
  std::lock_guard lock(seen_mutex);
  for (const auto& id : ids) {
    ASSERT_EQ(seen[id].size(), 3u) << id;
    EXPECT_EQ(seen[id][0], JobState::queued);
    EXPECT_EQ(seen[id][1], JobState::running);
    EXPECT_EQ(seen[id][2], JobState::succeeded);
  }
}

TEST_F(JobEngineTest, ADeletedJobStaysDeletedEvenIfItsWorkerWritesLate) {
  // A client that sees "succeeded" and deletes at once races the worker's
  // final record write; the deletion must win, also across a restart.
  std::vector<std::string> ids;
  {
    JobManager m(config(2, 64));
    for (int i = 0; i < 30; ++i) {
      const auto s = m.submit(sphere_stl(1.0 + 0.01 * i, 1), "s.stl", json{{"grid", {{"resolution", 8}}}});
      wait_finished(m, s.id);
      EXPECT_EQ(m.cancel_or_delete(s.id), JobManager::RemoveResult::deleted);
      ids.push_back(s.id);
    }
    m.shutdown(5s);  // every worker has finished writing
  }
  for (const auto& id : ids) EXPECT_FALSE(std::filesystem::exists(dir_ + "/jobs/" + id)) << id;
  JobManager again(config());
  for (const auto& id : ids) EXPECT_FALSE(again.get(id)) << id;
}

TEST_F(JobEngineTest, ExpiredJobsAreRemoved) {
  JobManagerConfig c = config();
  c.result_ttl = 1s;
  JobManager m(c);
  const auto s = m.submit(sphere_stl(), "s.stl", json{{"grid", {{"resolution", 16}}}});
  wait_finished(m, s.id);
  EXPECT_TRUE(m.get(s.id));  // kept until its time is up
  std::this_thread::sleep_for(1100ms);
  // The background expirer may already have removed it (it runs every
  // second); either way, once expire_now() returns it is gone.
  m.expire_now();
  EXPECT_FALSE(m.get(s.id));
  EXPECT_FALSE(std::filesystem::exists(dir_ + "/jobs/" + s.id));
}

}  // namespace
}  // namespace voxd::server
