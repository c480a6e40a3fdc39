// The Redis job store and queue against a real redis-server: URL parsing,
// blobs split into chunks and read back whole, a blob written twice kept
// once, deletion reaching every key, and the queue's capacity and leases.
#include <gtest/gtest.h>

#include <filesystem>
#include <set>
#include <thread>

#include "server/jobs/job_record.h"
#include "server/jobs/local_job_store.h"
#include "server/redis/redis_job_queue.h"
#include "server/redis/redis_job_store.h"
#include "voxd/error.h"
#include "support/redis_process.h"
#include "support/run_process.h"
#include "support/test_meshes.h"

namespace voxd::server {
namespace {

TEST(RedisUrl, ParsesTheFormsTheDocsName) {
  const RedisUrl a = parse_redis_url("redis://:s3cret@cache.internal:6380/2");
  EXPECT_EQ(a.host, "cache.internal");
  EXPECT_EQ(a.port, 6380);
  EXPECT_EQ(a.password, "s3cret");
  EXPECT_EQ(a.db, 2);
  EXPECT_EQ(a.redacted(), "redis://:***@cache.internal:6380/2");
  const RedisUrl b = parse_redis_url("redis://localhost");
  EXPECT_EQ(b.port, 6379);
  EXPECT_EQ(b.db, 0);
  const RedisUrl c = parse_redis_url("unix:///run/redis/redis.sock?db=3");
  EXPECT_EQ(c.socket_path, "/run/redis/redis.sock");
  EXPECT_EQ(c.db, 3);
  for (const char* bad : {"http://x", "redis://:pw@", "redis://h:99999", "redis://h:1/x", "unix://relative"})
    EXPECT_THROW(parse_redis_url(bad), std::invalid_argument) << bad;
}

class RedisStoreTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test::make_temp_dir("voxd-redis");
    redis_ = std::make_unique<test::RedisProcess>(dir_ + "/redis");
    pool_ = std::make_shared<RedisPool>(parse_redis_url(redis_->url()));
    RedisBackendOptions o;
    o.chunk_bytes = 1000;  // many chunks from small blobs
    o.replica_id = "test";
    store_ = std::make_unique<RedisJobStore>(pool_, o);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  JobSnapshot record(const std::string& id, JobState state) {
    JobSnapshot s;
    s.id = id;
    s.state = state;
    s.created_at = format_time(std::chrono::system_clock::now());
    s.params = nlohmann::json::object();
    s.job = std::make_shared<const api::JobParams>(api::parse_job_params(s.params));
    s.grid.dims = {4, 4, 4};
    s.grid.voxel_size = 1.0;
    s.content_hash = "ab" + id;
    return s;
  }
  long long keys() { return pool_->command({"DBSIZE"}).integer(); }

  std::string dir_;
  std::unique_ptr<test::RedisProcess> redis_;
  std::shared_ptr<RedisPool> pool_;
  std::unique_ptr<RedisJobStore> store_;
};

TEST_F(RedisStoreTest, BlobsAreChunkedReadBackWholeAndWrittenOnce) {
  store_->save(record("j1", JobState::running));
  std::vector<std::uint8_t> bytes(4321);
  for (std::size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<std::uint8_t>(i * 7 + 3);
  EXPECT_TRUE(store_->write_blob("j1", "volume", [&](ByteSink& s) { s.write(bytes.data(), bytes.size()); }));
  EXPECT_EQ(pool_->command({"HGET", "voxd:blob:j1:volume", "chunks"}).text(), "5");
  EXPECT_EQ(store_->read_blob("j1", "volume"), bytes);
  // The same blob again (the job run twice): the first is kept, the second's
  // chunks are dropped.
  const long long before = keys();
  std::vector<std::uint8_t> other(bytes.size(), 1);
  EXPECT_FALSE(store_->write_blob("j1", "volume", [&](ByteSink& s) { s.write(other.data(), other.size()); }));
  EXPECT_EQ(keys(), before);
  EXPECT_EQ(store_->read_blob("j1", "volume"), bytes);
  // Read front to back as it is needed (issue #37, finding 7: never copied
  // whole first), in reads of any size: the same bytes, and no spool file.
  auto stored = store_->volume_rle("j1");
  ASSERT_TRUE(stored);
  EXPECT_EQ(stored->size(), bytes.size());
  for (std::size_t piece : {std::size_t{1}, std::size_t{7}, std::size_t{1000}, std::size_t{65536}}) {
    auto source = stored->open();
    std::vector<std::uint8_t> got, buffer(piece);
    while (const std::size_t n = source->read(buffer.data(), buffer.size())) got.insert(got.end(), buffer.begin(), buffer.begin() + n);
    EXPECT_EQ(got, bytes) << "reads of " << piece;
  }
  EXPECT_FALSE(std::filesystem::exists(dir_ + "/spool"));
  // A failed write leaves nothing.
  EXPECT_THROW(store_->write_blob("j1", "layer:x.u8", [&](ByteSink& s) {
    s.write(bytes.data(), bytes.size());
    throw std::runtime_error("encoder failed");
  }), std::runtime_error);
  EXPECT_EQ(keys(), before);
  // Nothing is written for a job that is gone.
  EXPECT_FALSE(store_->write_blob("nope", "volume", [&](ByteSink& s) { s.write(bytes.data(), 10); }));
  // A reader whose blob is deleted meanwhile fails, never ends short.
  {
    auto source = stored->open();
    std::uint8_t first[10];
    ASSERT_EQ(source->read(first, sizeof first), sizeof first);
    pool_->command({"DEL", "voxd:chunk:j1:volume:" + std::string(pool_->command({"HGET", "voxd:blob:j1:volume", "gen"}).text()) + ":2"});
    std::vector<std::uint8_t> rest(100000);
    EXPECT_THROW({ while (source->read(rest.data(), rest.size()) > 0) {} }, voxd::Error);
  }
}

// Kept results read back whole, or straight into a buffer of their size
// (a kept thickness map into its volume), from either store: the same
// bytes, and nothing for a missing key or a buffer of another size.
void expect_artifacts_read_back(const JobStore& store, const std::string& id) {
  std::string bytes(3 << 20, '\0');  // larger than any stream's buffer, zeros included
  for (std::size_t i = 0; i < bytes.size(); i += 3) bytes[i] = static_cast<char>(i * 31 + 7);
  bytes.back() = 'z';
  store.save_artifact(id, "map.f32", bytes);
  const auto whole = store.load_artifact(id, "map.f32");
  ASSERT_TRUE(whole);
  EXPECT_TRUE(*whole == bytes);
  std::string into(bytes.size(), 'x');
  EXPECT_TRUE(store.load_artifact_into(id, "map.f32", into));
  EXPECT_TRUE(into == bytes);
  std::string shorter(bytes.size() - 1, 'x'), longer(bytes.size() + 1, 'x');
  EXPECT_FALSE(store.load_artifact_into(id, "map.f32", shorter));
  EXPECT_FALSE(store.load_artifact_into(id, "map.f32", longer));
  EXPECT_FALSE(store.load_artifact(id, "none.f32"));
  EXPECT_FALSE(store.load_artifact_into(id, "none.f32", into));
  store.save_artifact(id, "empty", "");
  ASSERT_TRUE(store.load_artifact(id, "empty"));
  EXPECT_TRUE(store.load_artifact(id, "empty")->empty());
}

TEST_F(RedisStoreTest, ArtifactsReadBackWholeOrIntoABufferOfTheirSize) {
  store_->save(record("j1", JobState::succeeded));
  expect_artifacts_read_back(*store_, "j1");
  const LocalJobStore local(dir_ + "/local");
  local.save(record("j2", JobState::succeeded));
  expect_artifacts_read_back(local, "j2");
}

TEST_F(RedisStoreTest, TransitionsAreCompareAndSetAndRemovalReachesEveryKey) {
  JobSnapshot s = record("j2", JobState::queued);
  store_->save(s);
  store_->save_input("j2", {1, 2, 3}, "part.stl");
  s.state = JobState::running;
  EXPECT_TRUE(store_->transition(s, {JobState::queued}));
  EXPECT_FALSE(store_->transition(s, {JobState::queued})) << "moved on already";
  EXPECT_EQ(store_->load("j2")->state, JobState::running);
  EXPECT_EQ(store_->load_input("j2")->name_hint, "part.stl");
  store_->save_volume("j2", BitVolume(s.grid));
  store_->drop_input("j2");
  EXPECT_FALSE(store_->load_input("j2"));
  s.state = JobState::succeeded;
  EXPECT_TRUE(store_->transition(s, {JobState::running}));
  EXPECT_EQ(store_->succeeded_with_hash("abj2"), "j2");
  EXPECT_GT(pool_->command({"PTTL", "voxd:job:j2"}).integer(), 0) << "a finished job expires";
  EXPECT_GT(pool_->command({"PTTL", "voxd:blob:j2:volume"}).integer(), 0);
  std::size_t total = 0;
  EXPECT_EQ(store_->list(0, 10, &total, {}).size(), 1u);
  EXPECT_EQ(total, 1u);
  store_->remove("j2");
  EXPECT_FALSE(store_->load("j2"));
  EXPECT_FALSE(store_->succeeded_with_hash("abj2"));
  EXPECT_EQ(pool_->command({"KEYS", "voxd:*j2*"}).size(), 0u);
  EXPECT_EQ(store_->list(0, 10, &total, {}).size(), 0u);
  EXPECT_EQ(total, 0u);
}

TEST_F(RedisStoreTest, TheQueueIsBoundedAndALapsedLeaseIsClaimedWithItsDeliveryCount) {
  RedisQueueOptions o;
  o.capacity = 2;
  o.lease = std::chrono::milliseconds(300);
  o.consumer = "a";
  RedisJobQueue a(pool_, o);
  o.consumer = "b";
  RedisJobQueue b(pool_, o);
  for (const char* id : {"q1", "q2", "q3"}) store_->save(record(id, JobState::queued));
  EXPECT_TRUE(a.submit("q1"));
  EXPECT_TRUE(b.submit("q2"));
  EXPECT_FALSE(a.submit("q3")) << "the shared queue holds two";
  EXPECT_EQ(b.depth(), 2u);
  auto first = a.take(std::chrono::milliseconds(100));
  ASSERT_TRUE(first);
  EXPECT_EQ(first->id, "q1");
  EXPECT_EQ(first->deliveries, 1);
  EXPECT_EQ(a.depth(), 1u);
  EXPECT_TRUE(b.submit("q3")) << "a job taken leaves room";
  EXPECT_TRUE(b.cancel("q3"));
  // a stops renewing (its replica died): b sees q1 idle past the lease,
  // watches it for half a lease more by its own clock (its next look, a
  // second later), then claims it. Meanwhile it takes what is queued.
  std::this_thread::sleep_for(std::chrono::milliseconds(400));
  auto second = b.take(std::chrono::milliseconds(100));
  ASSERT_TRUE(second);
  EXPECT_EQ(second->id, "q2") << "q1 is only watched at first sight";
  std::this_thread::sleep_for(std::chrono::milliseconds(1100));
  auto claimed = b.take(std::chrono::milliseconds(100));
  ASSERT_TRUE(claimed);
  EXPECT_EQ(claimed->id, "q1");
  EXPECT_EQ(claimed->deliveries, 2);
  b.ack("q1");
  // Renewed leases are not claimed.
  for (int i = 0; i < 8; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(60));
    b.renew_leases();
  }
  o.consumer = "c";
  RedisJobQueue c(pool_, o);
  EXPECT_FALSE(c.take(std::chrono::milliseconds(10)));
  b.ack("q2");
  EXPECT_EQ(a.depth(), 0u);
  EXPECT_EQ(pool_->command({"XLEN", "voxd:queue"}).integer(), 0) << "acknowledged entries are deleted";
}

// A job's plan: tasks of about the bytes asked (whole slabs when a task
// holds one or more), at most kMaxSlabTasks, none for a job of one task;
// the ranges tile the grid. Task ids go to the queue and back.
TEST(SlabTaskPlan, TasksTileTheGridInWholeSlabsUpToTheCap) {
  Grid grid;
  grid.voxel_size = 1.0;
  grid.dims = {1000, 1000, 1001};  // 128000 bytes of bits a layer (rows of whole words)
  EXPECT_FALSE(plan_slab_tasks(grid, 16, 0)) << "0: never split";
  EXPECT_FALSE(plan_slab_tasks(grid, 16, 200'000'000)) << "one task holds the grid";
  const std::optional<SlabTaskPlan> plan = plan_slab_tasks(grid, 16, 128000 * 100);
  ASSERT_TRUE(plan);
  EXPECT_EQ(plan->task_layers, 96) << "100 layers, in whole slabs of 16";
  EXPECT_EQ(plan->tasks, 11);
  std::int64_t next = 0;
  for (std::int64_t i = 0; i < plan->tasks; ++i) {
    const LayerRange r = plan->range(i, grid.dims.z);
    EXPECT_EQ(r.begin, next);
    EXPECT_GT(r.end, r.begin);
    next = r.end;
  }
  EXPECT_EQ(next, grid.dims.z);
  const std::optional<SlabTaskPlan> small = plan_slab_tasks(grid, 64, 128000 * 5);
  ASSERT_TRUE(small);
  EXPECT_EQ(small->task_layers, 5) << "a task smaller than a slab is not made a slab";
  grid.dims.z = 100000;
  const std::optional<SlabTaskPlan> capped = plan_slab_tasks(grid, 1, 1);
  ASSERT_TRUE(capped);
  EXPECT_LE(capped->tasks, kMaxSlabTasks);
  EXPECT_GE(capped->tasks * capped->task_layers, grid.dims.z);

  EXPECT_EQ(slab_task_id("0123abcd", 7), "0123abcd/slab/7");
  const std::optional<SlabTaskRef> ref = parse_slab_task_id("0123abcd/slab/7");
  ASSERT_TRUE(ref);
  EXPECT_EQ(ref->job_id, "0123abcd");
  EXPECT_EQ(ref->index, 7);
  for (const char* not_a_task : {"0123abcd", "/slab/1", "0123abcd/slab/", "0123abcd/slab/-1", "0123abcd/slab/1x"})
    EXPECT_FALSE(parse_slab_task_id(not_a_task)) << not_a_task;
}

// A split on the queue: the tasks are queued once (past the capacity) and
// the job's entry ends with it, even when its entry was handed out twice;
// each task's blocks are kept once, counted once, and dropped with the plan.
// Issue #37, finding 6: Redis counts an entry's idle time through a stall
// of its own, so right after Redis resumes a running job looks abandoned.
// Its owner renews at its next tick: a replica that looked during that tick
// must not take the job over.
TEST_F(RedisStoreTest, AnEntryIdleOnlyThroughAStallIsNotTakenOver) {
  RedisQueueOptions o;
  o.lease = std::chrono::milliseconds(600);
  o.consumer = "owner";
  RedisJobQueue owner(pool_, o);
  o.consumer = "other";
  RedisJobQueue other(pool_, o);
  store_->save(record("s1", JobState::queued));
  ASSERT_TRUE(owner.submit("s1"));
  ASSERT_TRUE(owner.take(std::chrono::milliseconds(100)));
  // The owner cannot renew for longer than a lease (Redis stood still).
  std::this_thread::sleep_for(std::chrono::milliseconds(800));
  // Redis moves again: the other replica looks first, then the owner renews.
  EXPECT_FALSE(other.take(std::chrono::milliseconds(10))) << "taken over at the first look after a stall";
  owner.renew_leases();
  for (int i = 0; i < 4; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(350));
    owner.renew_leases();
    EXPECT_FALSE(other.take(std::chrono::milliseconds(10))) << "a renewed lease taken over, look " << i;
  }
  const RedisReply p = pool_->command({"XPENDING", "voxd:queue", "voxd:workers", "-", "+", "10"});
  ASSERT_EQ(p.size(), 1u);
  EXPECT_EQ(p.at(0).at(1).text(), "owner");
  EXPECT_EQ(p.at(0).at(3).integer(), 1) << "delivered once";
  owner.ack("s1");
}

TEST_F(RedisStoreTest, AJobIsSplitOnceAndItsTasksAreCountedAndDroppedOnce) {
  RedisQueueOptions o;
  o.capacity = 1;
  o.lease = std::chrono::milliseconds(200);
  o.consumer = "a";
  RedisJobQueue a(pool_, o);
  o.consumer = "b";
  RedisJobQueue b(pool_, o);
  store_->save(record("big", JobState::queued));
  ASSERT_TRUE(a.submit("big"));
  ASSERT_TRUE(a.take(std::chrono::milliseconds(100)));
  // a's lease lapses: b sees it, watches it a while, takes the same entry;
  // both split it.
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  EXPECT_FALSE(b.take(std::chrono::milliseconds(10)));
  std::this_thread::sleep_for(std::chrono::milliseconds(1100));
  const auto again = b.take(std::chrono::milliseconds(100));
  ASSERT_TRUE(again);
  ASSERT_EQ(again->id, "big");
  const SlabTaskPlan plan{3, 10};
  store_->save_plan("big", plan);
  const std::vector<std::string> tasks = {slab_task_id("big", 0), slab_task_id("big", 1), slab_task_id("big", 2)};
  b.split("big", tasks);
  a.split("big", tasks);
  EXPECT_EQ(pool_->command({"XLEN", "voxd:queue"}).integer(), 3) << "three tasks, past the capacity of one";
  std::set<std::string> taken;
  while (auto t = a.take(std::chrono::milliseconds(50))) taken.insert(t->id);
  EXPECT_EQ(taken, std::set<std::string>(tasks.begin(), tasks.end()));
  const std::optional<SharedSlabTasks::State> state = store_->state("big");
  ASSERT_TRUE(state);
  EXPECT_EQ(state->plan.tasks, 3);
  EXPECT_EQ(state->plan.task_layers, 10);
  EXPECT_FALSE(state->cancel_requested);

  EXPECT_EQ(store_->finish_task("big", 0, 5, 3), 0) << "a job not running counts no task";
  JobSnapshot running = record("big", JobState::running);
  ASSERT_TRUE(store_->transition(running, {JobState::queued}));
  for (std::int64_t i = 0; i < 3; ++i) {
    store_->write_blocks("big", i, [&](ByteSink& sink) { sink.write("abcd", 4); });
    // A task made twice keeps its first blocks.
    store_->write_blocks("big", i, [&](ByteSink& sink) { sink.write("wxyz", 4); });
  }
  EXPECT_FALSE(store_->task_done("big", 1));
  EXPECT_EQ(store_->finish_task("big", 1, 100, 3), 1);
  EXPECT_EQ(store_->finish_task("big", 1, 999, 3), 1) << "counted once, with its first count";
  EXPECT_TRUE(store_->task_done("big", 1));
  EXPECT_NEAR(store_->load("big")->progress, 0.95 / 3, 1e-6);
  EXPECT_EQ(store_->finish_task("big", 0, 20, 3), 2);
  EXPECT_EQ(store_->finish_task("big", 2, 3, 3), 3);
  EXPECT_EQ(store_->filled("big"), 123u);
  VectorSink joined;
  for (std::int64_t i = 0; i < 3; ++i) ASSERT_TRUE(store_->read_blocks("big", i, joined));
  EXPECT_EQ(std::string(joined.data.begin(), joined.data.end()), "abcdabcdabcd");
  store_->request_cancel("big");
  EXPECT_TRUE(store_->state("big")->cancel_requested);

  store_->drop_tasks("big");
  VectorSink none;
  EXPECT_FALSE(store_->read_blocks("big", 0, none));
  EXPECT_FALSE(store_->task_done("big", 1));
  EXPECT_EQ(store_->filled("big"), 0u);
  EXPECT_TRUE(store_->load("big")) << "the job itself stays";
  store_->remove("big");
  EXPECT_EQ(keys(), 1) << "only the queue stream is left";
}

}  // namespace
}  // namespace voxd::server
