#pragma once
// A real Debian `redis-server` child process on a loopback ephemeral port
// with its own directory (append-only file on), for the scale-out tests.
#include <sys/types.h>

#include <string>

namespace voxd::test {

class RedisProcess {
 public:
  // Starts redis-server in DIR (created) on a free loopback port; throws
  // when it does not answer within 10 s.
  explicit RedisProcess(std::string dir);
  ~RedisProcess();
  RedisProcess(const RedisProcess&) = delete;
  RedisProcess& operator=(const RedisProcess&) = delete;

  int port() const { return port_; }
  std::string url() const { return "redis://127.0.0.1:" + std::to_string(port_); }
  // SIGTERM (Redis flushes its append-only file and exits) and wait.
  void stop();
  // Starts again on the same port and directory: it reloads the AOF.
  void start();
  bool running() const { return pid_ > 0; }
  // SIGSTOP (true) or SIGCONT: Redis stands still, connections open, as in
  // a stall (a swap storm, a paused container, a long fork).
  void freeze(bool frozen);
  // redis-cli against it (e.g. "FLUSHALL"); its output. Throws on failure.
  std::string cli(const std::string& args) const;

 private:
  void launch();
  std::string dir_;
  int port_ = 0;
  pid_t pid_ = -1;
};

// Whether something accepts TCP connections on 127.0.0.1:port.
bool port_open(int port);

}  // namespace voxd::test
