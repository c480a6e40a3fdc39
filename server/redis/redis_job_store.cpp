#include "server/redis/redis_job_store.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <random>
#include <sstream>

#include <spdlog/spdlog.h>

#include "server/jobs/job_record.h"
#include "voxd/encode/number_text.h"
#include "voxd/error.h"

namespace voxd::server {
namespace {

using Clock = std::chrono::system_clock;

std::int64_t now_ms() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now().time_since_epoch()).count();
}

std::string random_hex(std::size_t n) {
  thread_local std::mt19937_64 rng{std::random_device{}() ^ (static_cast<std::uint64_t>(std::random_device{}()) << 32)};
  static constexpr char kHex[] = "0123456789abcdef";
  std::string s(n, '0');
  for (char& c : s) c = kHex[rng() & 15];
  return s;
}

std::string ms_text(std::chrono::milliseconds t) { return std::to_string(std::max<std::int64_t>(t.count(), 1)); }

// Scripts run atomically on Redis: each is one state change no other replica
// can interleave with. (Keys outside KEYS are touched: a single Redis, not a
// Redis Cluster, as docs/scale-out.md says.)

// KEYS: job, index, keys set, hash index key, the set of tenant indexes.
// ARGV: record, state, created ms, id, result ttl ms, allowed current states
// (",a,b," or "" for any), content hash (succeeded jobs), tenant ("" for
// none), tenant index, stored bytes.
constexpr const char* kWriteRecord = R"lua(
if ARGV[6] ~= '' then
  local cur = redis.call('HGET', KEYS[1], 'state')
  if not cur or not string.find(ARGV[6], ',' .. cur .. ',', 1, true) then return 0 end
end
redis.call('HSET', KEYS[1], 'record', ARGV[1], 'state', ARGV[2], 'tenant', ARGV[8], 'bytes', ARGV[10])
redis.call('ZADD', KEYS[2], ARGV[3], ARGV[4])
if ARGV[8] ~= '' then
  redis.call('ZADD', ARGV[9], ARGV[3], ARGV[4])
  redis.call('SADD', KEYS[5], ARGV[9])
end
local s = ARGV[2]
if s == 'succeeded' or s == 'failed' or s == 'cancelled' then
  redis.call('HDEL', KEYS[1], 'cancel', 'progress', 'live')
  redis.call('PEXPIRE', KEYS[1], ARGV[5])
  for _, k in ipairs(redis.call('SMEMBERS', KEYS[3])) do redis.call('PEXPIRE', k, ARGV[5]) end
  redis.call('PEXPIRE', KEYS[3], ARGV[5])
  if s == 'succeeded' and ARGV[7] ~= '' then
    redis.call('SET', KEYS[4], ARGV[4], 'PX', ARGV[5])
    redis.call('HSET', KEYS[1], 'hash', ARGV[7])
  end
end
return 1
)lua";

// KEYS: a tenant's index. ARGV: job key prefix. What the tenant's jobs hold
// now: {queued, running, stored bytes of the succeeded}; entries of records
// Redis expired are dropped on the way.
constexpr const char* kTenantUsage = R"lua(
local queued, running, bytes = 0, 0, 0
for _, id in ipairs(redis.call('ZRANGE', KEYS[1], 0, -1)) do
  local f = redis.call('HMGET', ARGV[1] .. id, 'state', 'bytes')
  if not f[1] then
    redis.call('ZREM', KEYS[1], id)
  elseif f[1] == 'queued' then queued = queued + 1
  elseif f[1] == 'running' then running = running + 1
  elseif f[1] == 'succeeded' then bytes = bytes + (tonumber(f[2]) or 0) end
end
return {queued, running, tostring(bytes)}
)lua";

// KEYS: keys set. The bytes of the job's blobs (their chunks).
constexpr const char* kStoredBytes = R"lua(
local n = 0
for _, k in ipairs(redis.call('SMEMBERS', KEYS[1])) do
  if redis.call('TYPE', k).ok == 'string' then n = n + redis.call('STRLEN', k) end
end
return tostring(n)
)lua";

// KEYS: manifest, job, keys set. ARGV: generation, chunks, size, ttl for a
// job not finished, chunk key prefix (ends with "GEN:").
constexpr const char* kCommitBlob = R"lua(
if redis.call('EXISTS', KEYS[2]) == 0 then return -1 end
if redis.call('EXISTS', KEYS[1]) == 1 then return 0 end
redis.call('HSET', KEYS[1], 'gen', ARGV[1], 'chunks', ARGV[2], 'size', ARGV[3])
local ttl = redis.call('PTTL', KEYS[2])
if ttl < 0 then ttl = tonumber(ARGV[4]) end
redis.call('PEXPIRE', KEYS[1], ttl)
for i = 0, tonumber(ARGV[2]) - 1 do redis.call('PEXPIRE', ARGV[5] .. i, ttl) end
redis.call('SADD', KEYS[3], KEYS[1])
if redis.call('PTTL', KEYS[3]) < ttl then redis.call('PEXPIRE', KEYS[3], ttl) end
return 1
)lua";

// KEYS: job, index, keys set. ARGV: id, hash index key prefix, tenant
// index key prefix.
constexpr const char* kRemoveJob = R"lua(
local t = redis.call('HGET', KEYS[1], 'tenant')
if t and t ~= '' then redis.call('ZREM', ARGV[3] .. t, ARGV[1]) end
local h = redis.call('HGET', KEYS[1], 'hash')
if h then
  local k = ARGV[2] .. h
  if redis.call('GET', k) == ARGV[1] then redis.call('DEL', k) end
end
for _, k in ipairs(redis.call('SMEMBERS', KEYS[3])) do redis.call('DEL', k) end
redis.call('DEL', KEYS[3], KEYS[1])
redis.call('ZREM', KEYS[2], ARGV[1])
return 1
)lua";

// KEYS: source keys set, target keys set, source volume manifest. ARGV:
// source blob prefix, target blob prefix, source chunk prefix, target chunk
// prefix, ttl. Copies the volume and the layers (not the artifacts).
constexpr const char* kShareResults = R"lua(
if redis.call('EXISTS', KEYS[3]) == 0 then return 0 end
local function target(k, from, to)
  if string.sub(k, 1, #from) ~= from then return nil end
  local rest = string.sub(k, #from + 1)
  if rest == 'volume' or string.sub(rest, 1, 7) == 'volume:' or string.sub(rest, 1, 6) == 'layer:' or
     string.sub(rest, 1, 21) == 'artifact:surface-mesh' then return to .. rest end
  return nil
end
for _, k in ipairs(redis.call('SMEMBERS', KEYS[1])) do
  local dst = target(k, ARGV[1], ARGV[2]) or target(k, ARGV[3], ARGV[4])
  if dst and redis.call('EXISTS', k) == 1 then
    redis.call('COPY', k, dst, 'REPLACE')
    redis.call('PEXPIRE', dst, ARGV[5])
    redis.call('SADD', KEYS[2], dst)
  end
end
redis.call('PEXPIRE', KEYS[2], ARGV[5])
return 1
)lua";

// KEYS: the running jobs' records. ARGV: their progress ("" to leave it:
// a split job's moves as its tasks finish), then their live state (JSON of
// stage and analyses, "" to leave it). Returns per job
// "1" when its cancellation was asked, "gone" when it was deleted, "ended"
// when it ended already (a slab task of a job another task ended), "" else.
constexpr const char* kReportRunning = R"lua(
local out = {}
for i, k in ipairs(KEYS) do
  local state = redis.call('HGET', k, 'state')
  if state ~= false and state ~= 'running' then
    out[i] = 'ended'
  elseif state then
    if ARGV[i] ~= '' then redis.call('HSET', k, 'progress', ARGV[i]) end
    if ARGV[#KEYS + i] ~= '' then redis.call('HSET', k, 'live', ARGV[#KEYS + i]) end
    out[i] = redis.call('HGET', k, 'cancel') or ''
  else
    out[i] = 'gone'
  end
end
return out
)lua";

// KEYS: job. Marks a running job's cancellation as asked.
constexpr const char* kRequestCancel = R"lua(
if redis.call('HGET', KEYS[1], 'state') == 'running' then
  redis.call('HSET', KEYS[1], 'cancel', '1')
  return 1
end
return 0
)lua";

// KEYS: job. ARGV: tasks, task layers. The plan of a job still there.
constexpr const char* kSavePlan = R"lua(
if redis.call('EXISTS', KEYS[1]) == 0 then return 0 end
redis.call('HSET', KEYS[1], 'tasks', ARGV[1], 'task_layers', ARGV[2])
return 1
)lua";

// KEYS: job, tasks hash, keys set. ARGV: index, voxels, tasks, ttl. Counts
// a task of a running job done (once) and moves its progress; the number
// of its tasks done, 0 when it is no longer running.
constexpr const char* kFinishTask = R"lua(
if redis.call('HGET', KEYS[1], 'state') ~= 'running' then return 0 end
redis.call('HSETNX', KEYS[2], ARGV[1], ARGV[2])
redis.call('SADD', KEYS[3], KEYS[2])
if redis.call('PTTL', KEYS[2]) < 0 then redis.call('PEXPIRE', KEYS[2], ARGV[4]) end
if redis.call('PTTL', KEYS[3]) < 0 then redis.call('PEXPIRE', KEYS[3], ARGV[4]) end
local done = redis.call('HLEN', KEYS[2])
redis.call('HSET', KEYS[1], 'progress', tostring(0.95 * done / tonumber(ARGV[3])))
return done
)lua";

// KEYS: keys set. ARGV: key prefixes. Deletes the job's keys that start
// with one of them (a blob: its manifest and its chunks of any generation).
constexpr const char* kDropPrefixed = R"lua(
for _, k in ipairs(redis.call('SMEMBERS', KEYS[1])) do
  for i = 1, #ARGV do
    if string.sub(k, 1, #ARGV[i]) == ARGV[i] then
      redis.call('DEL', k)
      redis.call('SREM', KEYS[1], k)
      break
    end
  end
end
return 1
)lua";

// Streams a blob into chunks of chunk_bytes, each stored as it fills.
class ChunkSink final : public ByteSink {
 public:
  ChunkSink(RedisPool& pool, std::string chunk_prefix, std::string keys_set, std::size_t chunk_bytes,
            std::chrono::milliseconds ttl, std::uint64_t max_bytes)
      : pool_(pool), prefix_(std::move(chunk_prefix)), keys_(std::move(keys_set)), chunk_bytes_(chunk_bytes),
        ttl_(ms_text(ttl)), max_bytes_(max_bytes) {
    buffer_.reserve(std::min<std::size_t>(chunk_bytes_, std::size_t{1} << 20));
  }
  using ByteSink::write;
  void write(std::span<const std::uint8_t> bytes) override {
    total_ += bytes.size();
    if (max_bytes_ && total_ > max_bytes_)
      throw Error(ErrorCode::limit_exceeded, "the result is over the store's limit of " + std::to_string(max_bytes_) +
                                                 " bytes a result (--max-result-bytes); use a lower resolution");
    while (!bytes.empty()) {
      const std::size_t n = std::min(bytes.size(), chunk_bytes_ - buffer_.size());
      buffer_.insert(buffer_.end(), bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(n));
      bytes = bytes.subspan(n);
      if (buffer_.size() == chunk_bytes_) flush();
    }
  }
  void flush() {
    if (buffer_.empty()) return;
    const std::string key = prefix_ + std::to_string(chunks_);
    const std::string_view value(reinterpret_cast<const char*>(buffer_.data()), buffer_.size());
    written_.push_back(key);
    pool_.pipeline({{"SET", key, value, "PX", ttl_}, {"SADD", keys_, key}, {"PEXPIRE", keys_, ttl_}});
    ++chunks_;
    buffer_.clear();
  }
  std::size_t chunks() const { return chunks_; }
  std::uint64_t total() const { return total_; }
  // Best effort: a failed write or a lost race leaves nothing behind.
  void discard() noexcept {
    try {
      for (const std::string& key : written_) pool_.pipeline({{"DEL", key}, {"SREM", keys_, key}});
    } catch (const std::exception&) {
      // Redis went away: the chunks expire by themselves.
    }
  }

 private:
  RedisPool& pool_;
  std::string prefix_, keys_;
  std::size_t chunk_bytes_;
  std::string ttl_;
  std::uint64_t max_bytes_;
  std::vector<std::uint8_t> buffer_;
  std::vector<std::string> written_;
  std::size_t chunks_ = 0;
  std::uint64_t total_ = 0;
};

std::string from_states(std::initializer_list<JobState> states) {
  std::string text = ",";
  for (JobState s : states) text += std::string(to_string(s)) + ",";
  return text;
}

std::int64_t created_ms(const JobSnapshot& job) {
  if (job.created_at.empty()) return now_ms();
  return std::chrono::duration_cast<std::chrono::milliseconds>(parse_time(job.created_at).time_since_epoch()).count();
}

}  // namespace

RedisJobStore::RedisJobStore(std::shared_ptr<RedisPool> pool, RedisBackendOptions options)
    : pool_(std::move(pool)), options_(std::move(options)) {}

bool RedisJobStore::write_record(const JobSnapshot& job, const std::string& from) const {
  const std::string record = stored_record(job).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  const std::string created = std::to_string(created_ms(job));
  const std::string hash = job.state == JobState::succeeded ? job.content_hash : std::string();
  const RedisReply r = pool_->command({"EVAL", kWriteRecord, "5", key("job", job.id), options_.prefix + "jobs",
                                       key("keys", job.id), key("hash", hash), options_.prefix + "tenant-indexes", record,
                                       to_string(job.state), created, job.id, ms_text(options_.result_ttl), from, hash,
                                       job.labels.tenant, tenant_index(job.labels.tenant), std::to_string(job.stored_bytes)});
  return r.integer() == 1;
}

void RedisJobStore::save(const JobSnapshot& job) const { write_record(job, ""); }

bool RedisJobStore::transition(const JobSnapshot& job, std::initializer_list<JobState> from) const {
  return write_record(job, from_states(from));
}

namespace {

// A job from the reply to HMGET job record progress live: the record, with
// the live progress, stage and analyses of a running job.
JobSnapshot record_of(const RedisReply& fields) {
  JobSnapshot job = job_from_json(nlohmann::json::parse(fields.at(0).text()));
  if (job.state != JobState::running) return job;
  if (!fields.at(1).is_nil()) job.progress = parse_number<double>(fields.at(1).text()).value_or(job.progress);
  if (!fields.at(2).is_nil()) {
    const nlohmann::json live = nlohmann::json::parse(fields.at(2).text(), nullptr, /*allow_exceptions=*/false);
    if (live.is_object()) {
      if (live.contains("stage") && live["stage"].is_string()) job.stage = live["stage"];
      if (live.contains("analyses") && live["analyses"].is_array()) job.analyses = live["analyses"];
    }
  }
  return job;
}

}  // namespace

std::optional<JobSnapshot> RedisJobStore::load(const std::string& id) const {
  const RedisReply r = pool_->command({"HMGET", key("job", id), "record", "progress", "live"});
  if (r.at(0).is_nil()) return std::nullopt;
  return record_of(r);
}

std::vector<JobSnapshot> RedisJobStore::list(std::size_t offset, std::size_t limit, std::size_t* total,
                                             const JobFilter& filter) const {
  // The unnamed tenant's jobs have no index of their own: they are found
  // among all, as are names and tags.
  const bool unnamed = filter.tenant && filter.tenant->empty();
  const std::string index = filter.tenant && !unnamed ? tenant_index(*filter.tenant) : options_.prefix + "jobs";
  if (filter.by_label() || unnamed) return list_matching(index, offset, limit, total, filter);
  const std::string first = std::to_string(offset), last = std::to_string(offset + std::max<std::size_t>(limit, 1) - 1);
  const std::vector<RedisReply> page = pool_->pipeline({{"ZCARD", index}, {"ZREVRANGE", index, first, last}});
  std::size_t count = static_cast<std::size_t>(page[0].integer());
  std::vector<JobSnapshot> jobs;
  if (limit == 0 || page[1].size() == 0) {
    if (total) *total = count;
    return jobs;
  }
  std::vector<std::string> ids;
  for (std::size_t i = 0; i < page[1].size(); ++i) ids.emplace_back(page[1].at(i).text());
  std::size_t gone = 0;
  jobs = load_listed(index, ids, &gone);
  count = count > gone ? count - gone : 0;
  if (total) *total = count;
  return jobs;
}

std::vector<JobSnapshot> RedisJobStore::load_listed(const std::string& index, const std::vector<std::string>& ids,
                                                    std::size_t* gone) const {
  std::vector<RedisArgs> gets;
  std::vector<std::string> keys;
  keys.reserve(ids.size());
  for (const std::string& id : ids) keys.push_back(key("job", id));
  for (const std::string& k : keys) gets.push_back({"HMGET", k, "record", "progress", "live"});
  const std::vector<RedisReply> records = pool_->pipeline(gets);
  std::vector<JobSnapshot> jobs;
  for (std::size_t i = 0; i < records.size(); ++i) {
    if (records[i].at(0).is_nil()) {
      // Expired by Redis since: not listed, and no longer counted.
      pool_->command({"ZREM", index, ids[i]});
      ++*gone;
      continue;
    }
    try {
      jobs.push_back(record_of(records[i]));
    } catch (const std::exception& e) {
      spdlog::warn("job store: skipping unreadable record {}: {}", keys[i], e.what());
    }
  }
  return jobs;
}

// Names and tags are in the records only: the index is read newest first,
// a page of records at a time, and every match counted.
std::vector<JobSnapshot> RedisJobStore::list_matching(const std::string& index, std::size_t offset, std::size_t limit,
                                                      std::size_t* total, const JobFilter& filter) const {
  constexpr long long kPage = 500;
  std::vector<JobSnapshot> out;
  std::size_t matched = 0;
  for (long long first = 0;; first += kPage) {
    const RedisReply ids = pool_->command({"ZREVRANGE", index, std::to_string(first), std::to_string(first + kPage - 1)});
    std::vector<std::string> page;
    for (std::size_t i = 0; i < ids.size(); ++i) page.emplace_back(ids.at(i).text());
    std::size_t gone = 0;
    for (JobSnapshot& s : load_listed(index, page, &gone)) {
      if (!filter.matches(s)) continue;
      if (matched >= offset && out.size() < limit) out.push_back(std::move(s));
      ++matched;
    }
    first -= static_cast<long long>(gone);
    if (page.size() < static_cast<std::size_t>(kPage)) break;
  }
  if (total) *total = matched;
  return out;
}

TenantUsage RedisJobStore::usage(const std::string& tenant) const {
  if (tenant.empty()) return {};  // the unnamed tenant has no quotas
  const RedisReply r = pool_->command({"EVAL", kTenantUsage, "1", tenant_index(tenant), options_.prefix + "job:"});
  TenantUsage u;
  u.queued = static_cast<std::uint64_t>(r.at(0).integer());
  u.running = static_cast<std::uint64_t>(r.at(1).integer());
  u.stored_bytes = parse_number<std::uint64_t>(r.at(2).text()).value_or(0);
  return u;
}

std::uint64_t RedisJobStore::stored_bytes(const std::string& id) const {
  const RedisReply r = pool_->command({"EVAL", kStoredBytes, "1", key("keys", id)});
  return parse_number<std::uint64_t>(r.text()).value_or(0);
}

std::optional<RedisJobStore::BlobManifest> RedisJobStore::manifest(const std::string& id, const std::string& name) const {
  const RedisReply m = pool_->command({"HMGET", blob_key(id, name), "gen", "chunks", "size"});
  if (m.at(0).is_nil()) return std::nullopt;
  return BlobManifest{key("chunk", id) + ":" + name + ":" + std::string(m.at(0).text()) + ":",
                      parse_number<std::size_t>(m.at(1).text()).value_or(0), parse_number<std::uint64_t>(m.at(2).text()).value_or(0)};
}

bool RedisJobStore::read_chunks(const std::string& id, const std::string& name,
                                const std::function<void(std::string_view)>& chunk) const {
  const std::optional<BlobManifest> m = manifest(id, name);
  if (!m) return false;
  const std::string& prefix = m->chunk_prefix;
  const std::size_t chunks = m->chunks;
  const std::uint64_t size = m->size;
  std::uint64_t read = 0;
  // A few chunks a round trip: fewer round trips, bounded replies.
  constexpr std::size_t kBatch = 4;
  for (std::size_t first = 0; first < chunks; first += kBatch) {
    std::vector<std::string> keys;
    for (std::size_t i = first; i < std::min(chunks, first + kBatch); ++i) keys.push_back(prefix + std::to_string(i));
    std::vector<RedisArgs> gets;
    for (const std::string& k : keys) gets.push_back({"GET", k});
    for (const RedisReply& reply : pool_->pipeline(gets)) {
      if (reply.is_nil()) return false;  // expired or deleted while read
      read += reply.text().size();
      chunk(reply.text());
    }
  }
  return read == size;
}

std::optional<std::vector<std::uint8_t>> RedisJobStore::read_blob(const std::string& id, const std::string& name) const {
  std::vector<std::uint8_t> bytes;
  if (!read_chunks(id, name, [&](std::string_view c) { bytes.insert(bytes.end(), c.begin(), c.end()); }))
    return std::nullopt;
  return bytes;
}

bool RedisJobStore::write_blob(const std::string& id, const std::string& name,
                               const std::function<void(ByteSink&)>& write) const {
  const std::string gen = random_hex(16);
  const std::string chunk_prefix = key("chunk", id) + ":" + name + ":" + gen + ":";
  const bool is_result = name == "volume" || name.rfind("layer:", 0) == 0;
  ChunkSink sink(*pool_, chunk_prefix, key("keys", id), options_.chunk_bytes, options_.inflight_ttl,
                 is_result ? options_.max_result_bytes : 0);
  try {
    write(sink);
    sink.flush();
  } catch (...) {
    sink.discard();
    throw;
  }
  const RedisReply r = pool_->command({"EVAL", kCommitBlob, "3", blob_key(id, name), key("job", id), key("keys", id), gen,
                                       std::to_string(sink.chunks()), std::to_string(sink.total()),
                                       ms_text(options_.inflight_ttl), chunk_prefix});
  if (r.integer() == 1) return true;
  sink.discard();  // an earlier run's identical blob is kept, or the job is gone
  return false;
}

namespace {

// Where a blob's chunks are: prefix + index, `chunks` of them, `size` bytes.
struct ChunkList {
  std::shared_ptr<RedisPool> pool;
  std::string prefix;
  std::size_t chunks = 0;
  std::uint64_t size = 0;
};

// A blob's chunks, read as they are needed in slices of up to 1 MiB: a
// reader holds a slice, never the blob, however slowly its client reads.
class ChunkSource final : public ByteSource {
 public:
  explicit ChunkSource(ChunkList list) : list_(std::move(list)) {}
  std::size_t read(std::uint8_t* out, std::size_t size) override {
    if (at_ == slice_.size()) next_slice();
    const std::size_t n = std::min(size, slice_.size() - at_);
    if (n > 0) std::memcpy(out, slice_.data() + at_, n);
    at_ += n;
    return n;
  }

 private:
  static constexpr std::size_t kSlice = std::size_t{1} << 20;
  void next_slice() {
    slice_.clear();
    at_ = 0;
    while (slice_.empty()) {
      if (chunk_ == list_.chunks) {
        if (read_ != list_.size) gone();
        return;
      }
      const std::string key = list_.prefix + std::to_string(chunk_);
      const std::string first = std::to_string(offset_), last = std::to_string(offset_ + kSlice - 1);
      // GETRANGE answers "" for a key that is gone: EXISTS tells them apart.
      const std::vector<RedisReply> r = list_.pool->pipeline({{"EXISTS", key}, {"GETRANGE", key, first, last}});
      if (r[0].integer() != 1) gone();
      const std::string_view bytes = r[1].text();
      slice_.assign(bytes.begin(), bytes.end());
      read_ += bytes.size();
      if (bytes.size() < kSlice) {  // the chunk's end
        ++chunk_;
        offset_ = 0;
      } else {
        offset_ += kSlice;
      }
    }
  }
  [[noreturn]] static void gone() {
    throw Error(ErrorCode::io_error, "the stored result was deleted or expired while it was read");
  }

  ChunkList list_;
  std::vector<std::uint8_t> slice_;
  std::size_t at_ = 0;
  std::size_t chunk_ = 0;
  std::uint64_t offset_ = 0, read_ = 0;
};

class ChunkedBlob final : public StoredBlob {
 public:
  explicit ChunkedBlob(ChunkList list) : list_(std::move(list)) {}
  std::uint64_t size() const override { return list_.size; }
  std::unique_ptr<ByteSource> open() const override { return std::make_unique<ChunkSource>(list_); }

 private:
  ChunkList list_;
};

}  // namespace

std::shared_ptr<const StoredBlob> RedisJobStore::stored_blob(const std::string& id, const std::string& name) const {
  const std::optional<BlobManifest> m = manifest(id, name);
  if (!m) return nullptr;
  return std::make_shared<const ChunkedBlob>(ChunkList{pool_, m->chunk_prefix, m->chunks, m->size});
}

std::optional<std::string> RedisJobStore::load_artifact(const std::string& id, const std::string& key_name) const {
  auto bytes = read_blob(id, "artifact:" + key_name);
  if (!bytes) return std::nullopt;
  return std::string(bytes->begin(), bytes->end());
}

void RedisJobStore::save_artifact(const std::string& id, const std::string& key_name, std::string_view bytes) const {
  write_blob(id, "artifact:" + key_name, [&](ByteSink& sink) { sink.write(bytes.data(), bytes.size()); });
}

void RedisJobStore::save_volume(const std::string& id, const BitVolume& volume) const {
  write_volume(id, [&](ByteSink& sink) { write_rle(volume, sink); });
}

void RedisJobStore::write_volume(const std::string& id, const std::function<void(ByteSink&)>& write) const {
  write_blob(id, "volume", write);
}

std::shared_ptr<const BitVolume> RedisJobStore::load_volume(const std::string& id) const {
  const auto bytes = read_blob(id, "volume");
  if (!bytes) return nullptr;
  return std::make_shared<const BitVolume>(read_rle_bits(*bytes, kStoredVolumeLimits));
}

std::shared_ptr<const StoredBlob> RedisJobStore::volume_rle(const std::string& id) const { return stored_blob(id, "volume"); }

void RedisJobStore::save_layer(const std::string& id, const std::string& name, const ValueVolume& values) const {
  write_layer(id, name, values, [&](ByteSink& sink) { encode_volume(values, VolumeFormat::rle, sink); });
}

void RedisJobStore::write_layer(const std::string& id, const std::string& name, const ValueVolume& type,
                                const std::function<void(ByteSink&)>& write) const {
  write_blob(id, "layer:" + name + "." + value_type_name(type), write);
}

namespace {
constexpr const char* kValueTypes[] = {"u8", "f32", "rgba8"};
}

std::shared_ptr<const ValueVolume> RedisJobStore::load_layer(const std::string& id, const std::string& name) const {
  for (const char* type : kValueTypes)
    if (const auto bytes = read_blob(id, "layer:" + name + "." + type))
      return std::make_shared<const ValueVolume>(read_stored_layer(type, *bytes));
  return nullptr;
}

std::shared_ptr<const StoredBlob> RedisJobStore::layer_rle(const std::string& id, const std::string& name) const {
  for (const char* type : kValueTypes)
    if (auto blob = stored_blob(id, "layer:" + name + "." + type)) return blob;
  return nullptr;
}

void RedisJobStore::share_volume(const std::string& from_id, const std::string& to_id) const {
  const RedisReply r =
      pool_->command({"EVAL", kShareResults, "3", key("keys", from_id), key("keys", to_id), blob_key(from_id, "volume"),
                      key("blob", from_id) + ":", key("blob", to_id) + ":", key("chunk", from_id) + ":",
                      key("chunk", to_id) + ":", ms_text(options_.result_ttl)});
  if (r.integer() != 1) throw std::runtime_error("the original job's result is gone");
}

void RedisJobStore::remove(const std::string& id) const {
  pool_->command({"EVAL", kRemoveJob, "3", key("job", id), options_.prefix + "jobs", key("keys", id), id,
                  options_.prefix + "hash:", options_.prefix + "jobs:t:"});
}

std::uint64_t RedisJobStore::free_bytes() const {
  // Asked at most once a second: every submission checks it.
  const std::int64_t now = now_ms();
  if (now - free_checked_ms_.load() < 1000) return free_bytes_.load();
  const RedisReply info = pool_->command({"INFO", "memory"});
  std::uint64_t used = 0, max = 0;
  std::istringstream lines{std::string(info.text())};
  for (std::string line; std::getline(lines, line);) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.rfind("used_memory:", 0) == 0) used = parse_number<std::uint64_t>(line.substr(12)).value_or(0);
    if (line.rfind("maxmemory:", 0) == 0) max = parse_number<std::uint64_t>(line.substr(10)).value_or(0);
  }
  free_bytes_ = max == 0 ? UINT64_MAX : (max > used ? max - used : 0);
  free_checked_ms_ = now;
  return free_bytes_.load();
}

void RedisJobStore::save_input(const std::string& id, const std::vector<std::uint8_t>& bytes,
                               const std::string& name_hint) const {
  pool_->command({"HSET", key("job", id), "input_name", name_hint});
  const bool stored = write_blob(id, "input", [&](ByteSink& sink) { sink.write(bytes.data(), bytes.size()); });
  if (!stored) throw std::runtime_error("the job's record vanished while its upload was stored");
}

std::optional<SharedJobRecords::Input> RedisJobStore::load_input(const std::string& id) const {
  auto bytes = read_blob(id, "input");
  if (!bytes) return std::nullopt;
  const RedisReply name = pool_->command({"HGET", key("job", id), "input_name"});
  return Input{std::move(*bytes), std::string(name.text())};
}

void RedisJobStore::drop_input(const std::string& id) const {
  // No other blob's name starts with "input".
  pool_->command({"EVAL", kDropPrefixed, "1", key("keys", id), blob_key(id, "input"), key("chunk", id) + ":input:"});
}

std::optional<std::string> RedisJobStore::succeeded_with_hash(const std::string& hash) const {
  const RedisReply r = pool_->command({"GET", key("hash", hash)});
  if (r.is_nil()) return std::nullopt;
  return std::string(r.text());
}

void RedisJobStore::request_cancel(const std::string& id) const {
  pool_->command({"EVAL", kRequestCancel, "1", key("job", id)});
}

std::vector<std::string> RedisJobStore::report_running(const std::vector<RunningReport>& running) const {
  const std::string now = std::to_string(now_ms()), replicas = options_.prefix + "replicas";
  std::vector<RedisArgs> commands{{"ZADD", replicas, now, options_.replica_id}};
  std::vector<std::string> keys, progress, live;
  keys.reserve(running.size());
  progress.reserve(running.size());
  live.reserve(running.size());
  for (const RunningReport& r : running) {
    keys.push_back(key("job", r.id));
    progress.push_back(r.progress < 0 ? std::string() : std::to_string(r.progress));
    nlohmann::json state = nlohmann::json::object();
    if (r.progress >= 0 || !r.stage.empty()) state["stage"] = r.stage;
    if (!r.analyses.is_null()) state["analyses"] = r.analyses;
    live.push_back(state.empty() ? std::string() : state.dump());
  }
  const std::string n = std::to_string(keys.size());
  if (!keys.empty()) {
    RedisArgs eval{"EVAL", kReportRunning, n};
    for (const std::string& k : keys) eval.push_back(k);
    for (const std::string& p : progress) eval.push_back(p);
    for (const std::string& l : live) eval.push_back(l);
    commands.push_back(std::move(eval));
  }
  const std::vector<RedisReply> replies = pool_->pipeline(commands);
  std::vector<std::string> cancel;
  if (keys.empty()) return cancel;
  for (std::size_t i = 0; i < running.size(); ++i)
    if (!replies[1].at(i).text().empty()) cancel.push_back(running[i].id);
  return cancel;
}

bool RedisJobStore::reachable() const {
  try {
    return pool_->command({"PING"}).text() == "PONG";
  } catch (const std::exception&) {
    return false;
  }
}

std::size_t RedisJobStore::live_replicas() const {
  const std::string since = std::to_string(now_ms() - 5000);
  return static_cast<std::size_t>(pool_->command({"ZCOUNT", options_.prefix + "replicas", since, "+inf"}).integer());
}

void RedisJobStore::prune() const {
  pool_->command({"ZREMRANGEBYSCORE", options_.prefix + "replicas", "-inf", std::to_string(now_ms() - 3600 * 1000)});
  prune_index(options_.prefix + "jobs");
  const RedisReply tenants = pool_->command({"SMEMBERS", options_.prefix + "tenant-indexes"});
  for (std::size_t i = 0; i < tenants.size(); ++i) prune_index(std::string(tenants.at(i).text()));
}

// Records Redis expired still have their index entry: drop those, a page
// at a time.
void RedisJobStore::prune_index(const std::string& index) const {
  constexpr long long kPage = 1000;
  for (long long first = 0;; first += kPage) {
    const RedisReply ids = pool_->command({"ZRANGE", index, std::to_string(first), std::to_string(first + kPage - 1)});
    if (ids.size() == 0) return;
    std::vector<std::string> keys;
    for (std::size_t i = 0; i < ids.size(); ++i) keys.push_back(key("job", std::string(ids.at(i).text())));
    std::vector<RedisArgs> exists;
    for (const std::string& k : keys) exists.push_back({"EXISTS", k});
    const std::vector<RedisReply> found = pool_->pipeline(exists);
    RedisArgs zrem{"ZREM", index};
    std::vector<std::string> gone;
    for (std::size_t i = 0; i < found.size(); ++i)
      if (found[i].integer() == 0) gone.emplace_back(ids.at(i).text());
    for (const std::string& id : gone) zrem.push_back(id);
    if (!gone.empty()) pool_->command(zrem);
    first -= static_cast<long long>(gone.size());
    if (ids.size() < static_cast<std::size_t>(kPage)) return;
  }
}

}  // namespace voxd::server

namespace voxd::server {

namespace {
std::string blocks_name(std::int64_t index) { return "slab:" + std::to_string(index); }
}  // namespace

void RedisJobStore::save_plan(const std::string& id, const SlabTaskPlan& plan) const {
  pool_->command({"EVAL", kSavePlan, "1", key("job", id), std::to_string(plan.tasks), std::to_string(plan.task_layers)});
}

std::optional<SharedSlabTasks::State> RedisJobStore::state(const std::string& id) const {
  const RedisReply r = pool_->command({"HMGET", key("job", id), "tasks", "task_layers", "cancel"});
  if (r.at(0).is_nil() || r.at(1).is_nil()) return std::nullopt;
  State s;
  s.plan.tasks = parse_number<std::int64_t>(r.at(0).text()).value_or(0);
  s.plan.task_layers = parse_number<std::int64_t>(r.at(1).text()).value_or(0);
  if (s.plan.tasks < 1 || s.plan.task_layers < 1) return std::nullopt;
  s.cancel_requested = !r.at(2).is_nil();
  return s;
}

bool RedisJobStore::task_done(const std::string& id, std::int64_t index) const {
  return pool_->command({"HEXISTS", key("tasks", id), std::to_string(index)}).integer() == 1;
}

void RedisJobStore::write_blocks(const std::string& id, std::int64_t index,
                                 const std::function<void(ByteSink&)>& write) const {
  write_blob(id, blocks_name(index), write);
}

bool RedisJobStore::read_blocks(const std::string& id, std::int64_t index, ByteSink& sink) const {
  return read_chunks(id, blocks_name(index), [&](std::string_view c) { sink.write(c.data(), c.size()); });
}

std::int64_t RedisJobStore::finish_task(const std::string& id, std::int64_t index, std::uint64_t filled,
                                        std::int64_t tasks) const {
  return pool_
      ->command({"EVAL", kFinishTask, "3", key("job", id), key("tasks", id), key("keys", id), std::to_string(index),
                 std::to_string(filled), std::to_string(tasks), ms_text(options_.inflight_ttl)})
      .integer();
}

std::uint64_t RedisJobStore::filled(const std::string& id) const {
  const RedisReply r = pool_->command({"HVALS", key("tasks", id)});
  std::uint64_t total = 0;
  for (std::size_t i = 0; i < r.size(); ++i) total += parse_number<std::uint64_t>(r.at(i).text()).value_or(0);
  return total;
}

void RedisJobStore::drop_tasks(const std::string& id) const {
  const std::string blobs = blob_key(id, "slab:"), chunks = key("chunk", id) + ":slab:", tasks = key("tasks", id);
  pool_->command({"EVAL", kDropPrefixed, "1", key("keys", id), blobs, chunks, tasks});
}

}  // namespace voxd::server
