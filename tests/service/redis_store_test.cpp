// The Redis job store and queue against a real redis-server: URL parsing,
// blobs split into chunks and read back whole, a blob written twice kept
// once, deletion reaching every key, and the queue's capacity and leases.
#include <gtest/gtest.h>

#include <filesystem>
#include <thread>

#include "server/jobs/job_record.h"
#include "server/redis/redis_job_queue.h"
#include "server/redis/redis_job_store.h"
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
    o.spool_dir = dir_ + "/spool";
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
  // Mapped for reading slab by slab: the same bytes.
  auto mapped = store_->volume_rle("j1");
  ASSERT_TRUE(mapped);
  EXPECT_TRUE(std::equal(mapped->bytes().begin(), mapped->bytes().end(), bytes.begin(), bytes.end()));
  EXPECT_TRUE(std::filesystem::is_empty(dir_ + "/spool")) << "the spooled copy is unlinked once mapped";
  // A failed write leaves nothing.
  EXPECT_THROW(store_->write_blob("j1", "layer:x.u8", [&](ByteSink& s) {
    s.write(bytes.data(), bytes.size());
    throw std::runtime_error("encoder failed");
  }), std::runtime_error);
  EXPECT_EQ(keys(), before);
  // Nothing is written for a job that is gone.
  EXPECT_FALSE(store_->write_blob("nope", "volume", [&](ByteSink& s) { s.write(bytes.data(), 10); }));
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
  EXPECT_EQ(store_->list(0, 10, &total).size(), 1u);
  EXPECT_EQ(total, 1u);
  store_->remove("j2");
  EXPECT_FALSE(store_->load("j2"));
  EXPECT_FALSE(store_->succeeded_with_hash("abj2"));
  EXPECT_EQ(pool_->command({"KEYS", "voxd:*j2*"}).size(), 0u);
  EXPECT_EQ(store_->list(0, 10, &total).size(), 0u);
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
  // a stops renewing (its replica died): after the lease b claims q1.
  std::this_thread::sleep_for(std::chrono::milliseconds(400));
  auto claimed = b.take(std::chrono::milliseconds(100));
  ASSERT_TRUE(claimed);
  EXPECT_EQ(claimed->id, "q1");
  EXPECT_EQ(claimed->deliveries, 2);
  b.ack("q1");
  auto second = b.take(std::chrono::milliseconds(100));
  ASSERT_TRUE(second);
  EXPECT_EQ(second->id, "q2");
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

}  // namespace
}  // namespace voxd::server
