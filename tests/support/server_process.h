#pragma once
// A real `voxd serve` child process on a loopback ephemeral port, for
// integration tests that talk HTTP to it.
#include <sys/types.h>

#include <cstdint>
#include <string>
#include <vector>

namespace voxd::test {

// The voxd that serves: this build's, or VOXD_TEST_SERVE_BINARY's when set (to
// run the service tests against another build, e.g. an older one, and see a
// regression test fail there).
std::string serve_binary();

class ServerProcess {
 public:
  // Starts `voxd serve --host 127.0.0.1 --port 0 --data-dir DATA_DIR ARGS...`
  // and waits until it logs the port it listens on. Its log (stdout and
  // stderr) goes to LOG_PATH. Throws when it does not come up.
  // `launcher`, when given, runs first and gets the voxd command line as its
  // own arguments (e.g. a shell that mounts a small file system first).
  ServerProcess(const std::string& data_dir, const std::vector<std::string>& args = {},
                std::vector<std::string> env = {}, const std::vector<std::string>& launcher = {});
  ~ServerProcess();
  ServerProcess(const ServerProcess&) = delete;
  ServerProcess& operator=(const ServerProcess&) = delete;

  int port() const { return port_; }
  const std::string& log_path() const { return log_path_; }
  std::string log() const;
  // Sends SIGTERM and waits; returns the exit status (128+signal if killed).
  int stop(int timeout_seconds = 60);
  bool running() const { return pid_ > 0; }
  pid_t pid() const { return pid_; }
  // Peak resident memory so far (VmHWM), in bytes.
  std::uint64_t peak_rss() const;
  // SIGKILL, as a crash or the OOM killer would end it.
  void kill_hard();
  // SIGSTOP (true) or SIGCONT: the process stands still, as it is, until
  // thawed or killed (to look at what it holds at one instant).
  void freeze(bool frozen);

 private:
  pid_t pid_ = -1;
  int port_ = 0;
  std::string log_path_;
};

}  // namespace voxd::test
