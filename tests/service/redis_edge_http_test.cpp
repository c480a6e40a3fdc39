// A replica against a Redis that misbehaves the ways real ones do (issue
// #37's finding 5 and the probe wording of 9): Redis losing its data, Redis
// loading its data after a restart, Redis standing still, Redis near its
// maxmemory. Real `voxd serve --redis` processes on a real redis-server
// (and, for loading, a stand-in that answers every command LOADING).
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <chrono>
#include <thread>

#include "support/http_fixture.h"
#include "support/raw_socket.h"
#include "support/redis_process.h"

namespace voxd::test {
namespace {

using namespace std::chrono_literals;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

class RedisEdge : public HttpServiceTest {
 protected:
  void start_replica(const std::string& redis_url, std::vector<std::string> extra = {}) {
    std::vector<std::string> args = {"--redis", redis_url, "--workers", "1", "--redis-lease", "2"};
    args.insert(args.end(), extra.begin(), extra.end());
    start(args);
  }
  // /readyz's answer within `timeout` (status 0: none).
  std::pair<int, std::string> readyz(int timeout_s) {
    auto client = make_client(server_->port(), timeout_s);
    auto res = client->Get("/readyz");
    return res ? std::make_pair(res->status, res->body) : std::make_pair(0, std::string());
  }
  // Polls /readyz until it answers `status` (or 20 s pass).
  std::pair<int, std::string> readyz_becomes(int status) {
    std::pair<int, std::string> got;
    for (const auto until = Clock::now() + 20s; Clock::now() < until; std::this_thread::sleep_for(50ms))
      if ((got = readyz(5)).first == status) break;
    return got;
  }
  json small_job() {
    return submit(to_binary_stl(make_box({0, 0, 0}, {2, 3, 4})), R"({"grid": {"resolution": 12}})");
  }
};

// Finding 5: after Redis loses its data (FLUSHALL, or a restart without
// persistence) submissions work again at once, without restarting replicas.
TEST_F(RedisEdge, SubmissionsWorkAgainAfterRedisLosesItsData) {
  RedisProcess redis(dir_ + "/redis");
  start_replica(redis.url());
  finished(small_job());
  redis.cli("FLUSHALL");
  const json job = small_job();  // 202: the queue's group is made again
  finished(job);
  // A running queue, too: several in a row, all run.
  for (int i = 0; i < 3; ++i) finished(small_job());
  EXPECT_EQ(readyz(5).first, 200);
}

// A stand-in for a Redis that is loading its dataset: it accepts
// connections and answers every command with the LOADING error.
class LoadingRedis {
 public:
  LoadingRedis() {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 || ::listen(fd_, 16) != 0)
      throw std::runtime_error("cannot listen");
    socklen_t len = sizeof addr;
    ::getsockname(fd_, reinterpret_cast<sockaddr*>(&addr), &len);
    port_ = ntohs(addr.sin_port);
    accepter_ = std::thread([this] { accept_loop(); });
  }
  ~LoadingRedis() {
    stop_ = true;
    accepter_.join();
    for (auto& t : connections_) t.join();
    ::close(fd_);
  }
  std::string url() const { return "redis://127.0.0.1:" + std::to_string(port_); }
  int commands() const { return commands_; }

 private:
  void accept_loop() {
    while (!stop_) {
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, 100) <= 0) continue;
      const int c = ::accept(fd_, nullptr, nullptr);
      if (c >= 0) connections_.emplace_back([this, c] { serve(c); });
    }
  }
  // Counts each command (a RESP array of bulk strings) and answers it.
  void serve(int c) {
    std::string in;
    while (!stop_) {
      pollfd p{c, POLLIN, 0};
      if (::poll(&p, 1, 100) <= 0) continue;
      char buf[65536];
      const ssize_t n = ::recv(c, buf, sizeof buf, 0);
      if (n <= 0) break;
      in.append(buf, static_cast<std::size_t>(n));
      for (std::size_t used; (used = complete_command(in)) > 0;) {
        in.erase(0, used);
        ++commands_;
        const std::string reply = "-LOADING Redis is loading the dataset in memory\r\n";
        if (::send(c, reply.data(), reply.size(), MSG_NOSIGNAL) < 0) break;
      }
    }
    ::close(c);
  }
  // The bytes of the first whole command in `in`, or 0.
  static std::size_t complete_command(const std::string& in) {
    if (in.empty() || in[0] != '*') return 0;
    std::size_t at = in.find("\r\n");
    if (at == std::string::npos) return 0;
    const long count = std::stol(in.substr(1, at - 1));
    at += 2;
    for (long i = 0; i < count; ++i) {
      const std::size_t eol = in.find("\r\n", at);
      if (eol == std::string::npos || in[at] != '$') return 0;
      const std::size_t size = std::stoul(in.substr(at + 1, eol - at - 1));
      at = eol + 2 + size + 2;
      if (at > in.size()) return 0;
    }
    return at;
  }

  int fd_ = -1;
  int port_ = 0;
  std::atomic<bool> stop_{false};
  std::atomic<int> commands_{0};
  std::thread accepter_;
  std::vector<std::thread> connections_;
};

// Finding 5: while Redis loads its data, a submission is a 503 the client
// retries, not a 500, and the replica is not ready.
TEST_F(RedisEdge, ARedisLoadingItsDataIsA503) {
  LoadingRedis redis;
  start_replica(redis.url());
  const json p = expect_problem(post_multipart(http(), "/v1/jobs", to_binary_stl(make_box({0, 0, 0}, {1, 1, 1})),
                                               "part.stl", R"({"grid": {"resolution": 8}})"),
                                503, "backend-unavailable");
  EXPECT_NE(p.at("detail").get<std::string>().find("retry"), std::string::npos) << p.dump();
  const auto [status, body] = readyz_becomes(503);
  EXPECT_EQ(status, 503) << body;
  EXPECT_GT(redis.commands(), 0);
  // Ended before the stand-in goes: the replica's connections close with it.
  EXPECT_EQ(server_->stop(), 0) << server_->log();
}

// Finding 5: with Redis standing still, /readyz answers "not ready" at once
// (a probe's timeout is short), and "ready" again once Redis moves.
TEST_F(RedisEdge, AStalledRedisMakesTheReplicaNotReadyAtOnce) {
  RedisProcess redis(dir_ + "/redis");
  start_replica(redis.url());
  finished(small_job());
  EXPECT_EQ(readyz(5).first, 200);
  redis.freeze(true);
  std::this_thread::sleep_for(2500ms);  // longer than a probe would wait
  const auto t0 = Clock::now();
  const auto [status, body] = readyz(3);
  const auto took = Clock::now() - t0;
  redis.freeze(false);
  EXPECT_EQ(status, 503) << "no answer within 3 s while Redis stood still";
  EXPECT_NE(body.find("Redis"), std::string::npos) << body;
  EXPECT_LT(took, 1s);
  EXPECT_EQ(readyz_becomes(200).first, 200);
  finished(small_job());
}

// Finding 9: a replica whose Redis is near its maxmemory says so, not that
// a disk is full.
TEST_F(RedisEdge, ReadyzNamesRedisMemoryNotTheDisk) {
  RedisProcess redis(dir_ + "/redis");
  start_replica(redis.url(), {"--min-free-disk", std::to_string(std::uint64_t{1} << 40)});
  redis.cli("CONFIG SET maxmemory 64mb");
  const auto [status, body] = readyz_becomes(503);
  EXPECT_EQ(status, 503) << body;
  EXPECT_NE(body.find("maxmemory"), std::string::npos) << body;
  EXPECT_EQ(body.find("disk is full"), std::string::npos) << body;
}

// Finding 7: slow readers of a large stored result on a Redis replica hold a
// slice each, not a copy of the whole result in memory or on disk.
TEST_F(RedisEdge, SlowReadersOfAStoredResultHoldASliceEachNotACopy) {
  RedisProcess redis(dir_ + "/redis");
  start_replica(redis.url());
  // 128 plates across x: every row of the grid has 256 runs, so the stored
  // RLE is about 32 MB.
  std::vector<Mesh> plates;
  for (int i = 0; i < 128; ++i) plates.push_back(make_box({4.0 * i + 0.5, 0.5, 0.5}, {4.0 * i + 2.5, 511.5, 255.5}));
  const std::string id = finished(submit(to_binary_stl(concat(plates)),
                                         R"({"streaming": "on", "grid": {"voxel_size": 1, "origin": [0, 0, 0], "dims": [512, 512, 256]}})"));
  const std::uint64_t before = server_->peak_rss();
  constexpr int kReaders = 12;
  std::vector<std::unique_ptr<RawSocket>> readers;
  for (int i = 0; i < kReaders; ++i) {
    readers.push_back(std::make_unique<RawSocket>(server_->port()));
    readers.back()->send("GET /v1/jobs/" + id + "/volume?format=" + (i % 2 ? "rle" : "raw") + " HTTP/1.1\r\nHost: t\r\n\r\n");
  }
  // Each reads its first bytes, then stalls (its socket buffers fill).
  for (auto& r : readers) EXPECT_EQ(r->read_some(10s).rfind("HTTP/1.1 200", 0), 0u);
  std::this_thread::sleep_for(2s);
  const std::uint64_t after = server_->peak_rss();
  EXPECT_LT(after - before, std::uint64_t{96} << 20)
      << "peak RSS went from " << (before >> 20) << " MiB to " << (after >> 20) << " MiB with " << kReaders << " slow readers";
  EXPECT_FALSE(std::filesystem::exists(dir_ + "/data/spool")) << "a spool directory";
  // A reader that reads it all gets the whole result.
  readers.clear();
  const std::string rle = volume(id, "?format=rle");
  EXPECT_GT(rle.size(), std::size_t{24} << 20);
  const std::string raw = volume(id, "?format=raw");
  ASSERT_EQ(raw.size(), std::size_t{512} * 512 * 256);
  const std::size_t row = 512 * 300 + std::size_t{512} * 512 * 100;
  EXPECT_EQ(raw[row + 0], 0) << "x = 0 is outside every plate";
  EXPECT_NE(raw[row + 1], 0) << "x = 1 is inside the first plate";
  EXPECT_EQ(raw[row + 3], 0) << "x = 3 is between plates";
}

}  // namespace
}  // namespace voxd::test
