#include "server/redis/redis_job_queue.h"

#include <spdlog/spdlog.h>

#include "server/jobs/job_store.h"
#include "voxd/encode/number_text.h"

namespace voxd::server {
namespace {

// KEYS: stream, job. ARGV: group, capacity, job id. Queues the job unless
// the jobs waiting (in the stream, not yet handed out) fill the capacity;
// the job's record remembers its entry, for cancelling it.
constexpr const char* kSubmit = R"lua(
local n = redis.call('XLEN', KEYS[1])
local pending = redis.call('XPENDING', KEYS[1], ARGV[1])[1]
if n - pending >= tonumber(ARGV[2]) then return false end
local e = redis.call('XADD', KEYS[1], '*', 'job', ARGV[3])
redis.call('HSET', KEYS[2], 'entry', e)
return e
)lua";

// KEYS: stream. ARGV: group, consumer, entries... Renews the lease of each
// entry this consumer still holds; one another replica claimed is left to it.
constexpr const char* kRenew = R"lua(
local kept = 0
for i = 3, #ARGV do
  local p = redis.call('XPENDING', KEYS[1], ARGV[1], ARGV[i], ARGV[i], 1)
  if p[1] and p[1][2] == ARGV[2] then
    redis.call('XCLAIM', KEYS[1], ARGV[1], ARGV[2], 0, ARGV[i], 'JUSTID')
    kept = kept + 1
  end
end
return kept
)lua";

// KEYS: stream, job. ARGV: group, the job's entry, its tasks... Queues the
// tasks once per job (the record's "split" says it was) and ends the job's
// entry, in one step: a replica that dies before it changed nothing, one
// that dies after left nothing to redo but the tasks.
constexpr const char* kSplit = R"lua(
if redis.call('EXISTS', KEYS[2]) == 1 and redis.call('HSETNX', KEYS[2], 'split', '1') == 1 then
  for i = 3, #ARGV do redis.call('XADD', KEYS[1], '*', 'job', ARGV[i]) end
end
redis.call('XACK', KEYS[1], ARGV[1], ARGV[2])
redis.call('XDEL', KEYS[1], ARGV[2])
return 1
)lua";

// The job id in a stream entry [id, [field, value, ...]].
std::string job_of(const RedisReply& entry) {
  const RedisReply fields = entry.at(1);
  for (std::size_t i = 0; i + 1 < fields.size(); i += 2)
    if (fields.at(i).text() == "job") return std::string(fields.at(i + 1).text());
  return {};
}

}  // namespace

RedisJobQueue::RedisJobQueue(std::shared_ptr<RedisPool> pool, RedisQueueOptions options)
    : pool_(std::move(pool)), options_(std::move(options)), stream_(options_.prefix + "queue"),
      group_(options_.prefix + "workers") {
  try {
    ensure_group();
  } catch (const BackendUnavailable& e) {
    // The replica starts anyway (not ready); the group is made on first use.
    spdlog::warn("redis: {}", e.what());
  }
}

void RedisJobQueue::ensure_group() const {
  if (group_ready_) return;
  try {
    pool_->command({"XGROUP", "CREATE", stream_, group_, "0", "MKSTREAM"});
  } catch (const RedisError& e) {
    if (std::string(e.what()).find("BUSYGROUP") == std::string::npos) throw;
  }
  group_ready_ = true;
}

// Redis can lose the stream and its group while this replica runs (a
// restart without persistence, a FLUSHALL): the group is made again and the
// command retried, so submissions work again at once, not after a restart.
std::vector<RedisReply> RedisJobQueue::with_group(const std::vector<RedisArgs>& commands) const {
  ensure_group();
  try {
    return pool_->pipeline(commands);
  } catch (const RedisError& e) {
    if (std::string(e.what()).find("NOGROUP") == std::string::npos) throw;
    spdlog::warn("redis queue: the stream's consumer group is gone (Redis lost its data?): making it again");
    group_ready_ = false;
    ensure_group();
    return pool_->pipeline(commands);
  }
}

RedisReply RedisJobQueue::with_group(const RedisArgs& command) const {
  std::vector<RedisReply> replies = with_group(std::vector<RedisArgs>{command});
  return std::move(replies.front());
}

bool RedisJobQueue::submit(const std::string& id) {
  if (closed_) return false;
  const std::string capacity = std::to_string(options_.capacity);
  const RedisReply r = with_group({"EVAL", kSubmit, "2", stream_, job_key(id), group_, capacity, id});
  return !r.is_nil();
}

// An entry is taken over only when its owner has stayed silent for a lease
// by this replica's own clock, not Redis's: Redis counts an entry's idle
// time through a stall of its own, so right after Redis resumes every
// running job looks abandoned though its owner renews at its next tick.
// Entries idle past the lease are watched from the first time they are seen;
// one still idle past the lease half a lease later (its owner would have
// renewed it by then: renewals come every third of a lease) is claimed, and
// XCLAIM's own idle check makes the claim atomic against a renewal.
std::optional<TakenJob> RedisJobQueue::claim_stale() {
  const auto now = std::chrono::steady_clock::now();
  {
    // Once a second per replica is enough: a lease is many seconds.
    std::lock_guard lock(mutex_);
    if (now - last_claim_ < std::chrono::seconds(1)) return std::nullopt;
    last_claim_ = now;
  }
  const std::string idle = std::to_string(options_.lease.count());
  const RedisReply pending = with_group({"XPENDING", stream_, group_, "IDLE", idle, "-", "+", "16"});
  std::vector<std::string> ready;
  {
    std::lock_guard lock(mutex_);
    std::map<std::string, std::chrono::steady_clock::time_point> still;
    for (std::size_t i = 0; i < pending.size(); ++i) {
      const RedisReply p = pending.at(i);
      const std::string entry(p.at(0).text());
      if (p.at(1).text() == options_.consumer) continue;  // this replica's own: it renews them
      const auto seen = stale_since_.find(entry);
      const auto first = seen == stale_since_.end() ? now : seen->second;
      still[entry] = first;
      if (now - first >= options_.lease / 2) ready.push_back(entry);
    }
    stale_since_.swap(still);  // entries renewed or ended meanwhile are forgotten
  }
  for (const std::string& entry_id : ready) {
    const RedisReply claimed = with_group({"XCLAIM", stream_, group_, options_.consumer, idle, entry_id});
    if (claimed.size() == 0) continue;  // renewed, ended or claimed by another since the look
    const RedisReply entry = claimed.at(0);
    if (entry.is_nil() || !entry.is_array()) {
      acknowledge(entry_id);  // deleted from the stream (a cancelled job)
      continue;
    }
    const std::string job = job_of(entry);
    if (job.empty()) {
      acknowledge(entry_id);
      continue;
    }
    const RedisReply p = with_group({"XPENDING", stream_, group_, entry_id, entry_id, "1"});
    const int deliveries = p.size() > 0 ? static_cast<int>(p.at(0).at(3).integer()) : 2;
    spdlog::warn("redis queue: job {} was left by its worker (silent for a lease of {} ms): taking it over, delivery {}",
                 job, options_.lease.count(), deliveries);
    std::lock_guard lock(mutex_);
    stale_since_.erase(entry_id);
    entries_[job] = entry_id;
    return TakenJob{job, deliveries};
  }
  return std::nullopt;
}

std::optional<TakenJob> RedisJobQueue::take(std::chrono::milliseconds wait) {
  if (closed_) return std::nullopt;
  if (auto stale = claim_stale()) return stale;
  const std::string block = std::to_string(std::max<std::int64_t>(wait.count(), 1));
  const RedisReply r = with_group(
      {"XREADGROUP", "GROUP", group_, options_.consumer, "COUNT", "1", "BLOCK", block, "STREAMS", stream_, ">"});
  if (r.is_nil() || r.size() == 0) return std::nullopt;
  const RedisReply entries = r.at(0).at(1);
  if (entries.size() == 0) return std::nullopt;
  const RedisReply entry = entries.at(0);
  const std::string entry_id(entry.at(0).text());
  const std::string job = job_of(entry);
  if (job.empty()) {
    acknowledge(entry_id);
    return std::nullopt;
  }
  {
    std::lock_guard lock(mutex_);
    entries_[job] = entry_id;
  }
  if (closed_) {
    // Taken just as this process stops: give it straight back.
    release(job);
    return std::nullopt;
  }
  return TakenJob{job, 1};
}

void RedisJobQueue::acknowledge(const std::string& entry) {
  with_group({{"XACK", stream_, group_, entry}, {"XDEL", stream_, entry}});
}

std::optional<std::string> RedisJobQueue::forget(const std::string& id) {
  std::lock_guard lock(mutex_);
  auto it = entries_.find(id);
  if (it == entries_.end()) return std::nullopt;
  std::string entry = std::move(it->second);
  entries_.erase(it);
  return entry;
}

void RedisJobQueue::ack(const std::string& id) {
  const std::optional<std::string> entry = forget(id);
  if (!entry) return;
  try {
    acknowledge(*entry);
  } catch (const std::exception& e) {
    // Left pending and no longer renewed: its lease lapses, and the replica
    // that claims it finds the job ended and acknowledges it then.
    spdlog::warn("redis queue: cannot acknowledge job {} now ({}); it is acknowledged after its lease", id, e.what());
  }
}

void RedisJobQueue::release(const std::string& id) {
  const std::optional<std::string> entry = forget(id);
  if (!entry) return;
  // Idle as if its lease had run out long ago: the next claim anywhere takes it.
  const std::string idle = std::to_string(options_.lease.count() * 100);
  try {
    with_group({"XCLAIM", stream_, group_, options_.consumer, "0", *entry, "IDLE", idle, "JUSTID"});
  } catch (const std::exception& e) {
    // No longer renewed: another replica takes it once the lease lapses.
    spdlog::warn("redis queue: cannot hand job {} back now ({}); it is taken over after its lease", id, e.what());
  }
}

void RedisJobQueue::renew_leases() {
  RedisArgs args{"EVAL", kRenew, "1", stream_, group_, options_.consumer};
  std::vector<std::string> entries;
  {
    std::lock_guard lock(mutex_);
    const auto now = std::chrono::steady_clock::now();
    // Three renewals a lease: one lost round trip does not lose it.
    if (now - last_renew_ < options_.lease / 3) return;
    last_renew_ = now;
    for (const auto& [job, entry] : entries_) entries.push_back(entry);
  }
  if (entries.empty()) return;
  for (const std::string& e : entries) args.push_back(e);
  with_group(args);
}

void RedisJobQueue::split(const std::string& id, const std::vector<std::string>& tasks) {
  std::string entry;
  {
    std::lock_guard lock(mutex_);
    auto it = entries_.find(id);
    if (it == entries_.end()) throw std::logic_error("job " + id + " is split without being taken here");
    entry = it->second;
  }
  const std::string job = job_key(id);  // RedisArgs are views: kept alive here
  RedisArgs args{"EVAL", kSplit, "2", stream_, job, group_, entry};
  for (const std::string& t : tasks) args.push_back(t);
  with_group(args);
  forget(id);
}

bool RedisJobQueue::cancel(const std::string& id) {
  const RedisReply entry = with_group({"HGET", job_key(id), "entry"});
  if (entry.is_nil()) return false;
  const std::string e(entry.text());
  return with_group({"XDEL", stream_, e}).integer() == 1;
}

std::size_t RedisJobQueue::depth() const {
  const std::vector<RedisReply> r = with_group({{"XLEN", stream_}, {"XPENDING", stream_, group_}});
  const long long waiting = r[0].integer() - r[1].at(0).integer();
  return static_cast<std::size_t>(std::max(waiting, 0LL));
}

std::vector<std::string> RedisJobQueue::close() {
  closed_ = true;
  return {};
}

}  // namespace voxd::server
