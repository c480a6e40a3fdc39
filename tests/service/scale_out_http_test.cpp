// Scale-out: several real `voxd serve --redis` replicas on one real
// redis-server, all on loopback ephemeral ports, talked to as clients do.
#include <chrono>
#include <set>
#include <thread>

#include "support/http_fixture.h"
#include "support/redis_process.h"
#include "support/run_process.h"
#include "support/test_parts.h"
#include "voxd/encode/volume_format.h"

namespace voxd::test {
namespace {

using nlohmann::json;
using Clock = std::chrono::steady_clock;

// An organic closed part (test_parts.h) as a user uploads it.
std::vector<std::uint8_t> blob() { return to_binary_stl(test::part_mesh("blob.stl")); }

// How many times `needle` occurs in `text`.
std::size_t occurrences(const std::string& text, const std::string& needle) {
  std::size_t n = 0;
  for (auto at = text.find(needle); at != std::string::npos; at = text.find(needle, at + 1)) ++n;
  return n;
}

class ScaleOutTest : public HttpServiceTest {
 protected:
  void SetUp() override {
    HttpServiceTest::SetUp();
    redis_ = std::make_unique<RedisProcess>(dir_ + "/redis");
  }
  void TearDown() override {
    for (auto& r : replicas_) {
      if (r && r->running()) {
        EXPECT_EQ(r->stop(), 0) << r->log();
      }
    }
    replicas_.clear();
    HttpServiceTest::TearDown();
  }

  void start_replicas(int n, std::vector<std::string> extra = {}) {
    for (int i = 0; i < n; ++i) {
      std::vector<std::string> args = {"--redis", redis_->url(), "--workers", "1", "--redis-lease", "2"};
      args.insert(args.end(), extra.begin(), extra.end());
      replicas_.push_back(std::make_unique<ServerProcess>(dir_ + "/replica" + std::to_string(replicas_.size()), args));
      clients_.push_back(make_client(replicas_.back()->port()));
    }
  }
  httplib::Client& at(std::size_t i) { return *clients_.at(i); }
  // Waits for a job on replica i and expects it to succeed; its id.
  std::string finished_on(std::size_t i, const json& job) {
    const std::string id = job.at("id");
    const json done = wait_for_job(at(i), id);
    EXPECT_EQ(done.at("state"), "succeeded") << done.dump();
    schemas_->add("JobStatus", done.dump());
    return id;
  }

  // The replica whose worker finished the job (its log says so, just after
  // recording it); -1 if none.
  int runner(const std::string& id) const {
    for (int attempt = 0; attempt < 100; ++attempt) {
      int found = -1;
      for (std::size_t i = 0; i < replicas_.size(); ++i)
        if (replicas_[i]->log().find("job " + id + " succeeded") != std::string::npos) {
          EXPECT_EQ(found, -1) << "job " << id << " finished on two replicas";
          found = static_cast<int>(i);
        }
      if (found >= 0) return found;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return -1;
  }
  // The replica whose worker runs the job now (its log says so, just after
  // recording it); -1 if none.
  int running_on(const std::string& id) const {
    for (int attempt = 0; attempt < 100; ++attempt) {
      for (std::size_t i = 0; i < replicas_.size(); ++i)
        if (replicas_[i]->running() && replicas_[i]->log().find("job " + id + " running") != std::string::npos)
          return static_cast<int>(i);
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return -1;
  }
  // Whether the replica's log says `text` within a few seconds (it logs a
  // job's end just after recording it).
  bool logs_soon(std::size_t replica, const std::string& text) const {
    for (int i = 0; i < 100; ++i) {
      if (replicas_[replica]->log().find(text) != std::string::npos) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return false;
  }
  std::string volume_from(std::size_t replica, const std::string& id) {
    auto res = at(replica).Get(("/v1/jobs/" + id + "/volume").c_str());
    EXPECT_TRUE(res);
    if (!res) return {};
    EXPECT_EQ(res->status, 200) << res->body;
    return res->body;
  }

  // The Redis keys matching `pattern`, as redis-cli lists them.
  std::string redis_keys(const std::string& pattern) const {
    return run_process("redis-cli -p " + std::to_string(redis_->port()) + " --scan --pattern '" + pattern + "'").out;
  }
  // Slab tasks of job `id` each replica's log says it made.
  std::vector<std::size_t> tasks_done(const std::string& id) const {
    std::vector<std::size_t> done;
    for (const auto& r : replicas_) done.push_back(occurrences(r->log(), "slab task " + id + "/slab/"));
    return done;
  }

  std::unique_ptr<RedisProcess> redis_;
  std::vector<std::unique_ptr<ServerProcess>> replicas_;
  std::vector<std::unique_ptr<httplib::Client>> clients_;
};

// 60 jobs submitted round-robin to three replicas: each succeeds once, the
// shared list has each once, and each result fetched from a replica other
// than the one that ran it is the CLI's bytes.
TEST_F(ScaleOutTest, SixtyJobsOverThreeReplicasEachRunOnceWithTheCliBytes) {
  start_replicas(3);
  const auto mesh = to_binary_stl(make_torus({0, 0, 0}, 10, 3, 48, 24));
  std::vector<std::string> ids, params;
  for (int i = 0; i < 60; ++i) {
    params.push_back(R"({"grid":{"resolution":)" + std::to_string(16 + i) + "}}");
    const json job = expect_json(post_multipart(at(i % 3), "/v1/jobs", mesh, "torus.stl", params.back()), 202, "JobStatus");
    ids.push_back(job.at("id"));
  }
  for (std::size_t i = 0; i < ids.size(); ++i) {
    const json done = wait_for_job(at((i + 1) % 3), ids[i]);
    ASSERT_EQ(done.at("state"), "succeeded") << done.dump();
    schemas_->add("JobStatus", done.dump());
  }
  const json list = expect_json(at(2).Get("/v1/jobs?limit=100"), 200, "JobList");
  EXPECT_EQ(list.at("total"), 60);
  std::set<std::string> listed;
  for (const json& j : list.at("jobs")) {
    EXPECT_EQ(j.at("state"), "succeeded");
    listed.insert(j.at("id").get<std::string>());
  }
  EXPECT_EQ(listed, std::set<std::string>(ids.begin(), ids.end()));
  std::string logs;
  for (const auto& r : replicas_) logs += r->log();
  std::set<int> runners;
  for (std::size_t i = 0; i < ids.size(); ++i) {
    EXPECT_EQ(occurrences(logs, "job " + ids[i] + " succeeded"), 1u) << ids[i];
    const int ran = runner(ids[i]);
    ASSERT_GE(ran, 0) << ids[i];
    runners.insert(ran);
    const std::size_t other = static_cast<std::size_t>(ran + 1) % 3;
    EXPECT_EQ(volume_from(other, ids[i]), cli_volume(mesh, "torus.stl", params[i])) << "job " << i;
  }
  EXPECT_GE(runners.size(), 2u) << "the replicas share the work";
}

// kill -9 of the replica running long jobs: another replica takes each over
// once its lease runs out and finishes it with the same bytes.
TEST_F(ScaleOutTest, JobsOfAKilledReplicaAreFinishedByAnotherWithTheSameBytes) {
  start_replicas(3);
  const auto mesh = blob();
  const std::vector<std::string> params = {R"({"grid":{"resolution":520},"inside":"winding"})",
                                           R"({"grid":{"resolution":500},"inside":"winding"})"};
  std::vector<std::string> ids;
  for (const std::string& p : params)
    ids.push_back(expect_json(post_multipart(at(0), "/v1/jobs", mesh, "blob.stl", p), 202, "JobStatus").at("id"));
  wait_for_state(at(0), ids[0], "running");
  const int victim = running_on(ids[0]);
  ASSERT_GE(victim, 0);
  replicas_[static_cast<std::size_t>(victim)]->kill_hard();
  const std::size_t survivor = static_cast<std::size_t>(victim + 1) % 3;
  for (std::size_t i = 0; i < ids.size(); ++i) {
    const json done = wait_for_job(at(survivor), ids[i], 180);
    ASSERT_EQ(done.at("state"), "succeeded") << done.dump();
    const int ran = runner(ids[i]);
    EXPECT_NE(ran, victim);
    EXPECT_EQ(volume_from(survivor, ids[i]), cli_volume(mesh, "blob.stl", params[i])) << "job " << i;
  }
  std::string takeovers;
  for (const auto& r : replicas_)
    if (r->running()) takeovers += r->log();
  EXPECT_NE(takeovers.find("job " + ids[0] + " was left by its worker"), std::string::npos) << takeovers;
  const json list = expect_json(at(survivor).Get("/v1/jobs"), 200, "JobList");
  EXPECT_EQ(list.at("total"), 2);
}

// DELETE on one replica stops the job another replica runs, promptly.
TEST_F(ScaleOutTest, DeleteOnOneReplicaStopsAJobRunningOnAnother) {
  start_replicas(3);
  const std::string id = expect_json(post_multipart(at(0), "/v1/jobs", blob(), "blob.stl",
                                                    R"({"grid":{"resolution":900},"inside":"winding"})"),
                                     202, "JobStatus")
                             .at("id");
  wait_for_state(at(0), id, "running");
  const int runs = running_on(id);
  ASSERT_GE(runs, 0);
  const std::size_t other = static_cast<std::size_t>(runs + 1) % 3;
  const auto asked = Clock::now();
  expect_json(at(other).Delete(("/v1/jobs/" + id).c_str()), 202, "JobStatus");
  const json done = wait_for_job(at(other), id, 30);
  const double seconds = std::chrono::duration<double>(Clock::now() - asked).count();
  EXPECT_EQ(done.at("state"), "cancelled") << done.dump();
  // The job alone takes far longer; the cancellation travels through Redis
  // (polled every 100 ms) and the engine stops within ~50 ms.
  EXPECT_LT(seconds, 1.5);
  EXPECT_TRUE(logs_soon(static_cast<std::size_t>(runs), "job " + id + " cancelled"));
}

// Redis stopped and started again (append-only file): replicas go not
// ready and refuse submissions with backend-unavailable, then come back by
// themselves; jobs accepted before finish, finished results survive.
TEST_F(ScaleOutTest, RedisRestartLosesNoAcceptedJobAndNoResult) {
  start_replicas(2);
  const auto torus = to_binary_stl(make_torus({0, 0, 0}, 10, 3, 48, 24));
  const std::string small = R"({"grid":{"resolution":40}})";
  const std::string before = finished_on(1, expect_json(post_multipart(at(0), "/v1/jobs", torus, "torus.stl", small), 202, "JobStatus"));
  const std::string before_bytes = volume_from(1, before);
  ASSERT_EQ(before_bytes, cli_volume(torus, "torus.stl", small));

  // Accepted, then Redis goes away while they wait or run.
  std::vector<std::pair<std::string, std::string>> accepted;  // id, params
  for (int i = 0; i < 4; ++i) {
    const std::string p = i == 0 ? R"({"grid":{"resolution":420},"inside":"winding"})"
                                 : R"({"grid":{"resolution":)" + std::to_string(30 + i) + "}}";
    accepted.emplace_back(expect_json(post_multipart(at(static_cast<std::size_t>(i % 2)), "/v1/jobs", i == 0 ? blob() : torus,
                                                     i == 0 ? "blob.stl" : "torus.stl", p),
                                      202, "JobStatus")
                              .at("id"),
                          p);
  }
  redis_->stop();
  for (std::size_t r = 0; r < 2; ++r) {
    const auto until = Clock::now() + std::chrono::seconds(10);
    int status = 0;
    std::string body;
    while (Clock::now() < until && status != 503) {
      auto ready = at(r).Get("/readyz");
      status = ready ? ready->status : 0;
      body = ready ? ready->body : "";
      if (status != 503) std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    EXPECT_EQ(status, 503) << body;
    EXPECT_NE(body.find("Redis"), std::string::npos) << body;
  }
  const json refused = expect_problem(post_multipart(at(0), "/v1/jobs", torus, "torus.stl", small), 503, "backend-unavailable");
  EXPECT_NE(refused.at("detail").get<std::string>().find("retry"), std::string::npos);

  redis_->start();
  for (std::size_t r = 0; r < 2; ++r) {
    const auto until = Clock::now() + std::chrono::seconds(20);
    int status = 0;
    while (Clock::now() < until && status != 200) {
      auto res = at(r).Get("/readyz");
      status = res ? res->status : 0;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    EXPECT_EQ(status, 200) << "replica " << r << " did not reconnect";
  }
  for (const auto& [id, p] : accepted) {
    const json done = wait_for_job(at(1), id, 180);
    ASSERT_EQ(done.at("state"), "succeeded") << done.dump();
    const bool is_blob = p.find("winding") != std::string::npos;
    EXPECT_EQ(volume_from(0, id), cli_volume(is_blob ? blob() : torus, is_blob ? "blob.stl" : "torus.stl", p));
  }
  EXPECT_EQ(volume_from(0, before), before_bytes);
}

// What the embedded mode does by itself works across replicas: identical
// submissions answered from the first one's result (and mesh) on another replica,
// artifacts made on one replica served by another, a queued job cancelled
// from another replica at once, metrics with the shared queue and replicas.
TEST_F(ScaleOutTest, CachedResultsArtifactsCancellationAndMetricsAreShared) {
  start_replicas(2);
  const auto torus = to_binary_stl(make_torus({0, 0, 0}, 10, 3, 48, 24));
  const std::string p = R"({"grid":{"resolution":48}})";
  const std::string first = finished_on(1, expect_json(post_multipart(at(0), "/v1/jobs", torus, "torus.stl", p), 202, "JobStatus"));
  const json again = expect_json(post_multipart(at(1), "/v1/jobs", torus, "torus.stl", p), 202, "JobStatus");
  EXPECT_EQ(again.at("cached"), true) << again.dump();
  EXPECT_EQ(again.at("state"), "succeeded");
  const std::string second = again.at("id");
  EXPECT_EQ(volume_from(0, second), volume_from(1, first));
  // Deleting the original leaves the cached job's result.
  auto del = at(1).Delete(("/v1/jobs/" + first).c_str());
  ASSERT_TRUE(del);
  EXPECT_EQ(del->status, 204);
  expect_problem(at(0).Get(("/v1/jobs/" + first).c_str()), 404, "not-found");
  EXPECT_EQ(volume_from(1, second), cli_volume(torus, "torus.stl", p));
  // And the mesh it shares (kept_mesh.h): its thickness on the part
  // outlives the original, every vertex of the torus (48 x 24) in it.
  auto ply = at(0).Get(("/v1/jobs/" + second + "/thickness?format=ply").c_str());
  ASSERT_TRUE(ply);
  ASSERT_EQ(ply->status, 200) << ply->body;
  EXPECT_NE(ply->body.find("element vertex 1152\n"), std::string::npos) << ply->body.substr(0, 300);

  // An analysis made on one replica, served by the other.
  auto mass = at(0).Get(("/v1/jobs/" + second + "/analysis").c_str());
  ASSERT_TRUE(mass);
  ASSERT_EQ(mass->status, 200) << mass->body;
  auto mass_again = at(1).Get(("/v1/jobs/" + second + "/analysis").c_str());
  ASSERT_TRUE(mass_again);
  EXPECT_EQ(mass_again->body, mass->body);

  // A job queued behind long ones is cancelled from the other replica at once.
  std::vector<std::string> long_jobs;
  for (int i = 0; i < 2; ++i)
    long_jobs.push_back(expect_json(post_multipart(at(0), "/v1/jobs", blob(), "blob.stl",
                                                   R"({"grid":{"resolution":)" + std::to_string(600 + i) +
                                                       R"(},"inside":"winding"})"),
                                    202, "JobStatus")
                            .at("id"));
  const std::string queued =
      expect_json(post_multipart(at(0), "/v1/jobs", torus, "torus.stl", R"({"grid":{"resolution":77}})"), 202, "JobStatus").at("id");
  const json cancelled = expect_json(at(1).Delete(("/v1/jobs/" + queued).c_str()), 202, "JobStatus");
  EXPECT_EQ(cancelled.at("state"), "cancelled") << cancelled.dump();
  EXPECT_EQ(wait_for_job(at(0), queued, 5).at("state"), "cancelled");

  auto metrics = at(1).Get("/metrics");
  ASSERT_TRUE(metrics);
  EXPECT_NE(metrics->body.find("voxd_replicas_live 2"), std::string::npos) << metrics->body;
  EXPECT_NE(metrics->body.find("voxd_queue_depth"), std::string::npos);
  for (const std::string& id : long_jobs) at(1).Delete(("/v1/jobs/" + id).c_str());
  for (const std::string& id : long_jobs) EXPECT_EQ(wait_for_job(at(1), id, 30).at("state"), "cancelled");
}

// One huge job split into slab tasks over three replicas: every replica
// makes some of them, and the volume, put together by whichever made the
// last, is the CLI's bytes on one machine. Then a replica is killed while it
// holds a task: it loses only that task, which another replica redoes, and
// the volume is again the CLI's bytes.
TEST_F(ScaleOutTest, AHugeJobSplitIntoSlabTasksIsTheCliBytesAlsoWithAReplicaKilledMidJob) {
  // Tasks of 3 layers of bits (64 KiB), so that the job is dozens of them.
  start_replicas(3, {"--slab-task-bytes", "65536", "--max-result-bytes", "0"});
  // Many triangles: every task decodes and bins them all, so a task lasts
  // long enough to be caught running.
  const auto mesh = to_binary_stl(make_torus({0, 0, 0}, 10, 4, 640, 320));
  const std::string params = R"({"grid":{"resolution":400},"streaming":"on"})";
  const std::string id =
      expect_json(post_multipart(at(0), "/v1/jobs", mesh, "torus.stl", params), 202, "JobStatus").at("id");
  const json done = wait_for_job(at(1), id, 180);
  ASSERT_EQ(done.at("state"), "succeeded") << done.dump();
  schemas_->add("JobStatus", done.dump());
  const std::string expected = cli_volume(mesh, "torus.stl", params);
  // (Compared as a whole: a dump of megabytes on a failure says nothing.)
  for (std::size_t i = 0; i < 3; ++i) EXPECT_TRUE(volume_from(i, id) == expected) << "from replica " << i;
  const BitVolume voxels = read_rle_bits(std::span(reinterpret_cast<const std::uint8_t*>(expected.data()), expected.size()));
  EXPECT_EQ(done.at("filled_voxels").get<std::uint64_t>(), voxels.count());
  std::string logs;
  for (const auto& r : replicas_) logs += r->log();
  const std::size_t at_split = logs.find("job " + id + " split into ");
  ASSERT_NE(at_split, std::string::npos) << logs;
  const int tasks = std::stoi(logs.substr(at_split + ("job " + id + " split into ").size()));
  EXPECT_GT(tasks, 20);
  std::size_t made = 0, makers = 0;
  for (const std::size_t n : tasks_done(id)) {
    made += n;
    makers += n > 0 ? 1 : 0;
  }
  EXPECT_EQ(made, 2u * static_cast<std::size_t>(tasks)) << "each task logged running and done once";
  EXPECT_GE(makers, 2u) << "the replicas share the tasks";
  EXPECT_EQ(occurrences(logs, "job " + id + " put together from"), 1u);
  EXPECT_EQ(redis_keys("voxd:*" + id + ":slab:*"), "") << "the tasks' blocks are dropped once the job ends";
  EXPECT_EQ(redis_keys("voxd:tasks:" + id), "");

  // The same job a voxel larger: a replica is stopped still while it holds
  // a task it has not finished, then killed.
  const std::string params2 = R"({"grid":{"resolution":401},"streaming":"on"})";
  const std::string id2 =
      expect_json(post_multipart(at(0), "/v1/jobs", mesh, "torus.stl", params2), 202, "JobStatus").at("id");
  std::string lost;  // the task the killed replica held
  int victim = -1;
  for (int attempt = 0; attempt < 2000 && lost.empty(); ++attempt) {
    for (std::size_t i = 0; i < 3 && lost.empty(); ++i) {
      ServerProcess& r = *replicas_[i];
      r.freeze(true);
      const std::string log = r.log();
      for (auto at = log.find("slab task " + id2 + "/slab/"); at != std::string::npos;
           at = log.find("slab task " + id2 + "/slab/", at + 1)) {
        const std::size_t name_end = log.find(' ', at + 10);
        const std::string task = log.substr(at + 10, name_end - at - 10);
        if (log.compare(name_end, 9, " running ") == 0 && log.find("slab task " + task + " done") == std::string::npos)
          lost = task;
      }
      if (!lost.empty()) {
        r.kill_hard();
        victim = static_cast<int>(i);
      } else {
        r.freeze(false);
      }
    }
    if (lost.empty()) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ASSERT_FALSE(lost.empty()) << "no replica was caught holding a task";
  const std::size_t survivor = static_cast<std::size_t>(victim + 1) % 3;
  const json done2 = wait_for_job(at(survivor), id2, 180);
  ASSERT_EQ(done2.at("state"), "succeeded") << done2.dump();
  const std::string expected2 = cli_volume(mesh, "torus.stl", params2);
  EXPECT_TRUE(volume_from(survivor, id2) == expected2);
  std::string survivors;
  for (const auto& r : replicas_)
    if (r->running()) survivors += r->log();
  EXPECT_NE(survivors.find("job " + lost + " was left by its worker"), std::string::npos) << lost << "\n" << survivors;
  EXPECT_NE(survivors.find("slab task " + lost + " done"), std::string::npos) << lost;
}

// DELETE of a split job while its tasks run on both replicas: every task
// stops or is skipped, the job ends cancelled, and its tasks' blocks are
// dropped.
TEST_F(ScaleOutTest, DeletingASplitJobStopsItsTasksEverywhere) {
  start_replicas(2, {"--slab-task-bytes", "65536", "--max-result-bytes", "0"});
  const auto mesh = to_binary_stl(make_torus({0, 0, 0}, 10, 4, 640, 320));
  const std::string id = expect_json(post_multipart(at(0), "/v1/jobs", mesh, "torus.stl",
                                                    R"({"grid":{"resolution":400},"streaming":"on"})"),
                                     202, "JobStatus")
                             .at("id");
  for (int i = 0; i < 500; ++i) {
    const auto done = tasks_done(id);
    if (done[0] + done[1] >= 4) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  expect_json(at(1).Delete(("/v1/jobs/" + id).c_str()), 202, "JobStatus");
  const json done = wait_for_job(at(0), id, 30);
  EXPECT_EQ(done.at("state"), "cancelled") << done.dump();
  // Tasks under way when it ended stop within a keeper's tick (~100 ms;
  // a second here, for a loaded machine); none is made after: the logs
  // stop growing.
  std::this_thread::sleep_for(std::chrono::seconds(1));
  const auto after = tasks_done(id);
  std::this_thread::sleep_for(std::chrono::seconds(1));
  EXPECT_EQ(tasks_done(id), after);
  EXPECT_EQ(redis_keys("voxd:*" + id + ":slab:*"), "");
  EXPECT_EQ(redis_keys("voxd:tasks:" + id), "");
  EXPECT_EQ(expect_json(at(1).Get("/v1/jobs"), 200, "JobList").at("total"), 1);
}

}  // namespace
}  // namespace voxd::test
