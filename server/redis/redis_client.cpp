#include "server/redis/redis_client.h"

#include <sys/time.h>

#include <hiredis/hiredis.h>

#include "server/jobs/job_store.h"
#include "voxd/encode/number_text.h"

namespace voxd::server {

std::string RedisUrl::redacted() const {
  std::string text = socket_path.empty() ? "redis://" : "unix://";
  if (!socket_path.empty()) {
    text += socket_path;
    if (db) text.append("?db=").append(std::to_string(db));
    return text;
  }
  if (!password.empty()) text += ":***@";
  text.append(host).append(":").append(std::to_string(port));
  if (db) text.append("/").append(std::to_string(db));
  return text;
}

RedisUrl parse_redis_url(const std::string& url) {
  RedisUrl u;
  auto bad = [&](const std::string& why) {
    return std::invalid_argument("the Redis URL '" + url + "' " + why +
                                 "; use redis://[:password@]host:port[/db] or unix:///path/to/socket");
  };
  auto number = [&](std::string_view text, int max, const char* what) {
    const auto n = parse_number<int>(text);
    if (!n || *n < 0 || *n > max) throw bad(std::string("has a bad ") + what);
    return *n;
  };
  if (url.rfind("unix://", 0) == 0) {
    std::string rest = url.substr(7);
    const auto q = rest.find('?');
    if (q != std::string::npos) {
      const std::string query = rest.substr(q + 1);
      rest.resize(q);
      if (query.rfind("db=", 0) != 0) throw bad("has an unknown query (only db=N)");
      u.db = number(std::string_view(query).substr(3), 1 << 20, "database number");
    }
    if (rest.empty() || rest[0] != '/') throw bad("needs an absolute socket path");
    u.socket_path = rest;
    return u;
  }
  if (url.rfind("redis://", 0) != 0) throw bad("does not start with redis:// or unix://");
  std::string rest = url.substr(8);
  const auto at = rest.rfind('@');
  if (at != std::string::npos) {
    std::string userinfo = rest.substr(0, at);
    rest = rest.substr(at + 1);
    const auto colon = userinfo.find(':');
    // redis://:password@ (Redis 5 style) or redis://user:password@ (the user is ignored: AUTH password).
    u.password = colon == std::string::npos ? userinfo : userinfo.substr(colon + 1);
  }
  const auto slash = rest.find('/');
  if (slash != std::string::npos) {
    const std::string db = rest.substr(slash + 1);
    rest.resize(slash);
    if (!db.empty()) u.db = number(db, 1 << 20, "database number");
  }
  const auto colon = rest.rfind(':');
  if (colon != std::string::npos) {
    u.port = number(std::string_view(rest).substr(colon + 1), 65535, "port");
    rest.resize(colon);
  }
  if (rest.empty()) throw bad("has no host");
  u.host = rest;
  return u;
}

RedisReply::RedisReply(redisReply* owned)
    : root_(owned, [](redisReply* r) { freeReplyObject(r); }), node_(owned) {}

bool RedisReply::is_nil() const { return !node_ || node_->type == REDIS_REPLY_NIL; }
bool RedisReply::is_array() const { return node_ && node_->type == REDIS_REPLY_ARRAY; }
bool RedisReply::is_integer() const { return node_ && node_->type == REDIS_REPLY_INTEGER; }

long long RedisReply::integer() const {
  if (!is_integer()) throw RedisError("Redis answered with something other than an integer");
  return node_->integer;
}

std::string_view RedisReply::text() const {
  if (!node_ || (node_->type != REDIS_REPLY_STRING && node_->type != REDIS_REPLY_STATUS)) return {};
  return {node_->str, node_->len};
}

const redisReply* RedisReply::error() const { return node_ && node_->type == REDIS_REPLY_ERROR ? node_ : nullptr; }

std::size_t RedisReply::size() const { return is_array() ? node_->elements : 0; }

RedisReply RedisReply::at(std::size_t i) const {
  if (i >= size()) return RedisReply(root_, nullptr);
  return RedisReply(root_, node_->element[i]);
}

namespace {

timeval to_timeval(std::chrono::milliseconds t) {
  return timeval{static_cast<time_t>(t.count() / 1000), static_cast<suseconds_t>((t.count() % 1000) * 1000)};
}

// An error reply: out of memory is the store being full (HTTP 507); Redis
// loading its data after a restart, busy with a script, or a replica cut off
// from its master is Redis not available for now (HTTP 503, retry); the
// rest are bugs or misconfiguration.
[[noreturn]] void throw_error_reply(const redisReply* r) {
  const std::string text(r->str, r->len);
  if (text.rfind("OOM", 0) == 0)
    throw StorageFull("Redis is out of memory (maxmemory reached): " + text);
  for (const char* transient : {"LOADING", "BUSY ", "MASTERDOWN", "TRYAGAIN", "CLUSTERDOWN"})
    if (text.rfind(transient, 0) == 0) throw BackendUnavailable("Redis cannot answer for now: " + text);
  throw RedisError("Redis: " + text);
}

}  // namespace

RedisConnection::RedisConnection(const RedisUrl& url, std::chrono::milliseconds timeout) {
  const timeval tv = to_timeval(timeout);
  context_ = url.socket_path.empty() ? redisConnectWithTimeout(url.host.c_str(), url.port, tv)
                                     : redisConnectUnixWithTimeout(url.socket_path.c_str(), tv);
  if (!context_ || context_->err) {
    const std::string why = context_ ? context_->errstr : "out of memory";
    if (context_) redisFree(context_);
    context_ = nullptr;
    throw BackendUnavailable("cannot reach Redis at " + url.redacted() + ": " + why);
  }
  redisSetTimeout(context_, tv);
  if (url.socket_path.empty()) redisEnableKeepAlive(context_);
  try {
    if (!url.password.empty()) command({"AUTH", url.password});
    if (url.db != 0) {
      const std::string db = std::to_string(url.db);
      command({"SELECT", db});
    }
  } catch (...) {
    redisFree(context_);
    context_ = nullptr;
    throw;
  }
}

RedisConnection::~RedisConnection() {
  if (context_) redisFree(context_);
}

RedisReply RedisConnection::read_reply() {
  void* raw = nullptr;
  if (redisGetReply(context_, &raw) != REDIS_OK || !raw) {
    broken_ = true;
    throw BackendUnavailable(std::string("lost the connection to Redis: ") +
                             (context_->errstr[0] ? context_->errstr : "no reply"));
  }
  return RedisReply(static_cast<redisReply*>(raw));
}

RedisReply RedisConnection::command(const RedisArgs& args) {
  std::vector<RedisReply> replies = pipeline({args});
  return std::move(replies.front());
}

std::vector<RedisReply> RedisConnection::pipeline(const std::vector<RedisArgs>& commands) {
  if (broken_) throw BackendUnavailable("the connection to Redis is broken");
  std::vector<const char*> argv;
  std::vector<std::size_t> lengths;
  for (const RedisArgs& args : commands) {
    argv.clear();
    lengths.clear();
    for (std::string_view a : args) {
      argv.push_back(a.data());
      lengths.push_back(a.size());
    }
    if (redisAppendCommandArgv(context_, static_cast<int>(argv.size()), argv.data(), lengths.data()) != REDIS_OK) {
      broken_ = true;
      throw BackendUnavailable("cannot send to Redis: out of memory");
    }
  }
  std::vector<RedisReply> replies;
  replies.reserve(commands.size());
  for (std::size_t i = 0; i < commands.size(); ++i) replies.push_back(read_reply());
  for (const RedisReply& reply : replies)
    if (const redisReply* e = reply.error()) throw_error_reply(e);
  return replies;
}

RedisPool::RedisPool(RedisUrl url, std::chrono::milliseconds timeout) : url_(std::move(url)), timeout_(timeout) {}

RedisPool::Lease::~Lease() {
  if (!c_ || c_->broken()) return;
  std::lock_guard lock(pool_->mutex_);
  pool_->idle_.push_back(std::move(c_));
}

RedisPool::Lease RedisPool::lease() {
  {
    std::lock_guard lock(mutex_);
    if (!idle_.empty()) {
      auto c = std::move(idle_.back());
      idle_.pop_back();
      return Lease(*this, std::move(c));
    }
  }
  return Lease(*this, std::make_unique<RedisConnection>(url_, timeout_));
}

}  // namespace voxd::server
