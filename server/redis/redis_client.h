#pragma once
// A small synchronous Redis client over hiredis: a URL, replies that free
// themselves, and a pool of connections that replaces a broken one on the
// next use, so replicas reconnect by themselves when Redis comes back.
// Every call either answers or throws: BackendUnavailable when Redis cannot
// be reached, StorageFull when Redis is out of memory (maxmemory with
// noeviction), RedisError for any other error reply.
#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

struct redisContext;
struct redisReply;

namespace voxd::server {

// redis://[:password@]host:port[/db] or unix:///path/to/socket[?db=N].
struct RedisUrl {
  std::string host = "127.0.0.1";
  int port = 6379;
  std::string socket_path;  // set for unix://
  std::string password;
  int db = 0;
  // The URL without its password, for logs.
  std::string redacted() const;
};
// Throws std::invalid_argument with what is wrong in the URL.
RedisUrl parse_redis_url(const std::string& url);

// Redis answered with an error reply (a script's, a wrong type, ...).
class RedisError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// One reply, freed with it. Arrays' elements are views into the same reply.
class RedisReply {
 public:
  RedisReply() = default;
  explicit RedisReply(redisReply* owned);
  bool is_nil() const;
  bool is_array() const;
  bool is_integer() const;
  long long integer() const;     // throws unless an integer
  std::string_view text() const;  // a string or status; empty for nil
  std::size_t size() const;       // elements of an array
  RedisReply at(std::size_t i) const;  // a view of element i (shares ownership)
  const redisReply* error() const;     // the reply when it is an error, else null

 private:
  RedisReply(std::shared_ptr<redisReply> root, const redisReply* node) : root_(std::move(root)), node_(node) {}
  std::shared_ptr<redisReply> root_;
  const redisReply* node_ = nullptr;
};

using RedisArgs = std::vector<std::string_view>;

// One connection; not shared between threads (the pool hands it out).
class RedisConnection {
 public:
  RedisConnection(const RedisUrl& url, std::chrono::milliseconds timeout);  // throws BackendUnavailable
  ~RedisConnection();
  RedisConnection(const RedisConnection&) = delete;
  RedisConnection& operator=(const RedisConnection&) = delete;

  RedisReply command(const RedisArgs& args);
  // Sends every command, then reads every reply: one round trip. An error
  // reply throws after all replies were read (the connection stays usable).
  std::vector<RedisReply> pipeline(const std::vector<RedisArgs>& commands);
  bool broken() const { return broken_; }

 private:
  RedisReply read_reply();
  redisContext* context_ = nullptr;
  bool broken_ = false;
};

class RedisPool {
 public:
  RedisPool(RedisUrl url, std::chrono::milliseconds timeout = std::chrono::seconds(10));

  // A connection for one call; back in the pool when the lease ends (unless
  // it broke). Throws BackendUnavailable when Redis cannot be reached.
  class Lease {
   public:
    Lease(RedisPool& pool, std::unique_ptr<RedisConnection> c) : pool_(&pool), c_(std::move(c)) {}
    Lease(Lease&&) = default;
    ~Lease();
    RedisConnection* operator->() { return c_.get(); }

   private:
    RedisPool* pool_;
    std::unique_ptr<RedisConnection> c_;
  };
  Lease lease();

  // The usual case: one command, or one pipeline, on a pooled connection.
  RedisReply command(const RedisArgs& args) { return lease()->command(args); }
  std::vector<RedisReply> pipeline(const std::vector<RedisArgs>& commands) { return lease()->pipeline(commands); }
  const RedisUrl& url() const { return url_; }

 private:
  RedisUrl url_;
  std::chrono::milliseconds timeout_;
  std::mutex mutex_;
  std::vector<std::unique_ptr<RedisConnection>> idle_;
};

}  // namespace voxd::server
