#pragma once
// The job queue on Redis, shared by every replica: a Redis Stream (PREFIX
// queue) with one consumer group (PREFIX workers). Each replica is a
// consumer; a job handed to it stays in the group's pending list until it is
// acknowledged, after its result is stored. While a job runs its replica
// renews the lease (XCLAIM on its own pending entry, which resets the entry's
// idle time); an entry idle longer than the lease belongs to a replica that
// stopped, and the next take anywhere claims it (XAUTOCLAIM), counting one
// more delivery.
#include <atomic>
#include <chrono>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "server/jobs/job_queue.h"
#include "server/redis/redis_client.h"

namespace voxd::server {

struct RedisQueueOptions {
  std::string prefix = "voxd:";
  std::string consumer;     // this replica, unique among those on the Redis
  std::size_t capacity = 64;  // jobs waiting in the shared queue at most
  std::chrono::milliseconds lease = std::chrono::seconds(15);
};

class RedisJobQueue final : public JobQueue {
 public:
  // Creates the stream and the group if they are not there. Throws
  // BackendUnavailable when Redis cannot be reached.
  RedisJobQueue(std::shared_ptr<RedisPool> pool, RedisQueueOptions options);

  bool submit(const std::string& id) override;
  std::optional<TakenJob> take(std::chrono::milliseconds wait) override;
  bool closed() const override { return closed_.load(); }
  void ack(const std::string& id) override;
  void release(const std::string& id) override;
  void renew_leases() override;
  void split(const std::string& id, const std::vector<std::string>& tasks) override;
  bool cancel(const std::string& id) override;
  std::size_t depth() const override;
  std::vector<std::string> close() override;

 private:
  void ensure_group() const;
  // The commands, after making the group when Redis has lost it.
  std::vector<RedisReply> with_group(const std::vector<RedisArgs>& commands) const;
  RedisReply with_group(const RedisArgs& command) const;
  std::optional<TakenJob> claim_stale();
  // Drops a job taken here from the entries this replica renews; its entry.
  std::optional<std::string> forget(const std::string& id);
  // Ends an entry for good: acknowledged and deleted from the stream.
  void acknowledge(const std::string& entry);
  std::string job_key(const std::string& id) const { return options_.prefix + "job:" + id; }

  std::shared_ptr<RedisPool> pool_;
  RedisQueueOptions options_;
  std::string stream_, group_;
  std::atomic<bool> closed_{false};
  mutable std::atomic<bool> group_ready_{false};
  std::mutex mutex_;
  std::map<std::string, std::string> entries_;  // job id -> stream entry, of jobs taken here
  std::chrono::steady_clock::time_point last_claim_{}, last_renew_{};
  // Other replicas' entries seen idle past the lease, and since when (this
  // replica's clock): claim_stale takes one over only after watching it.
  std::map<std::string, std::chrono::steady_clock::time_point> stale_since_;
};

}  // namespace voxd::server
