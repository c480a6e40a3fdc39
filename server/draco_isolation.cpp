#include "server/draco_isolation.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <new>
#include <string>
#include <cstdio>
#include <thread>
#include <vector>

#include "voxd/error.h"

extern char** environ;

namespace voxd::server {
namespace {

using Clock = std::chrono::steady_clock;

// The child's answer: "VXM1", vertex and triangle counts (u64), the vertices
// (3 floats each) and the triangles (3 u32 each); or "VXE1", an ErrorCode
// (u32) and the message.
constexpr char kMeshTag[4] = {'V', 'X', 'M', '1'};
constexpr char kErrorTag[4] = {'V', 'X', 'E', '1'};
static_assert(sizeof(glm::vec3) == 12 && sizeof(std::array<std::uint32_t, 3>) == 12, "the answer's layout");

[[noreturn]] void refuse(const std::string& why) {
  throw Error(ErrorCode::malformed_input, "the Draco decoder " + why + "; the file is corrupt or hostile");
}

// How a transfer with the child ended: the deadline is told apart from the
// child's own end, whatever the clock says after a poll that returned early.
enum class Transfer { done, timed_out, failed };

// Waits for `events` until the deadline.
Transfer wait_for(int fd, short events, Clock::time_point deadline) {
  pollfd p{fd, events, 0};
  const auto left = std::chrono::ceil<std::chrono::milliseconds>(deadline - Clock::now()).count();
  if (left <= 0) return Transfer::timed_out;
  const int r = ::poll(&p, 1, static_cast<int>(left));
  if (r == 0) return Transfer::timed_out;
  return r > 0 || errno == EINTR ? Transfer::done : Transfer::failed;
}

Transfer send_all(int fd, const void* data, std::size_t size, Clock::time_point deadline) {
  const auto* p = static_cast<const char*>(data);
  while (size > 0) {
    if (const Transfer t = wait_for(fd, POLLOUT, deadline); t != Transfer::done) return t;
    const ssize_t n = ::send(fd, p, size, MSG_NOSIGNAL);
    if (n < 0 && (errno == EINTR || errno == EAGAIN)) continue;
    if (n <= 0) return Transfer::failed;
    p += n;
    size -= static_cast<std::size_t>(n);
  }
  return Transfer::done;
}

// Everything until EOF, at most `cap` bytes.
Transfer receive_all(int fd, std::vector<char>& out, std::size_t cap, Clock::time_point deadline) {
  char buf[1 << 16];
  for (;;) {
    if (const Transfer t = wait_for(fd, POLLIN, deadline); t != Transfer::done) return t;
    const ssize_t n = ::recv(fd, buf, sizeof buf, 0);
    if (n < 0 && (errno == EINTR || errno == EAGAIN)) continue;
    if (n < 0) return Transfer::failed;
    if (n == 0) return Transfer::done;
    if (out.size() + static_cast<std::size_t>(n) > cap) return Transfer::failed;
    out.insert(out.end(), buf, buf + n);
  }
}

template <class T>
T read_at(const std::vector<char>& bytes, std::size_t offset) {
  T v;
  std::memcpy(&v, bytes.data() + offset, sizeof v);
  return v;
}

Mesh parse_answer(const std::vector<char>& answer, std::uint64_t max_triangles) {
  if (answer.size() >= 8 && std::memcmp(answer.data(), kErrorTag, 4) == 0) {
    const auto code = static_cast<ErrorCode>(read_at<std::uint32_t>(answer, 4));
    std::string message(answer.begin() + 8, answer.end());
    switch (code) {  // only the codes a decoder throws; anything else is suspect
      case ErrorCode::malformed_input:
      case ErrorCode::truncated_input:
      case ErrorCode::non_finite_coordinates:
      case ErrorCode::no_usable_triangles:
      case ErrorCode::limit_exceeded:
      case ErrorCode::empty_input: throw Error(code, message);
      default: refuse("failed");
    }
  }
  if (answer.size() < 20 || std::memcmp(answer.data(), kMeshTag, 4) != 0) refuse("gave no answer");
  const auto vertices = read_at<std::uint64_t>(answer, 4), triangles = read_at<std::uint64_t>(answer, 12);
  if (triangles > max_triangles || vertices > 3 * max_triangles + 3 ||
      answer.size() != 20 + 12 * vertices + 12 * triangles)
    refuse("gave a malformed answer");
  Mesh mesh;
  mesh.vertices.resize(vertices);
  mesh.triangles.resize(triangles);
  std::memcpy(mesh.vertices.data(), answer.data() + 20, 12 * vertices);
  std::memcpy(mesh.triangles.data(), answer.data() + 20 + 12 * vertices, 12 * triangles);
  // The child is this program, but its answer is checked like any input.
  for (const auto& t : mesh.triangles)
    for (const std::uint32_t v : t)
      if (v >= vertices) refuse("gave a triangle outside its vertices");
  return mesh;
}

std::string describe_end(int status, const DracoIsolation& iso) {
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    if (sig == SIGXCPU) return "ran past its CPU limit of " + std::to_string(iso.max_cpu_seconds) + " s";
    if (sig == SIGKILL)
      return "was stopped: over its memory limit of " + std::to_string(iso.max_memory >> 20) +
             " MiB (--max-decode-memory) or its time";
    return std::string("crashed (") + strsignal(sig) + ")";
  }
  return "ended with status " + std::to_string(WEXITSTATUS(status)) + " and no answer";
}

[[maybe_unused]] std::uint64_t resident_bytes() {
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  unsigned long long pages = 0, resident = 0;
  if (f) {
    if (std::fscanf(f, "%llu %llu", &pages, &resident) != 2) resident = 0;
    std::fclose(f);
  }
  return resident * static_cast<std::uint64_t>(::sysconf(_SC_PAGESIZE));
}

void write_all_or_exit(int fd, const void* data, std::size_t size) {
  const auto* p = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t n = ::write(fd, p, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) std::_Exit(3);
    p += n;
    size -= static_cast<std::size_t>(n);
  }
}

}  // namespace

Mesh decode_draco_isolated(std::span<const std::uint8_t> data, const DracoIsolation& iso) {
  int fds[2];
  if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, fds) != 0)
    throw Error(ErrorCode::io_error, std::string("cannot start the Draco decoder: ") + std::strerror(errno));
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[1], 0);
  posix_spawn_file_actions_adddup2(&actions, fds[1], 1);
  posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
  std::vector<std::string> args = {"voxd", "decode-draco-isolated", std::to_string(iso.max_triangles),
                                   std::to_string(iso.max_memory), std::to_string(iso.max_cpu_seconds)};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::vector<std::string> env_strings;
#if defined(__SANITIZE_ADDRESS__)
  // ASan reserves terabytes of shadow memory, so no rlimit can bound the
  // child; its allocator's own limits do (a refused allocation throws
  // bad_alloc, which the decoder reports as a corrupt file).
  env_strings.push_back("ASAN_OPTIONS=detect_leaks=0:allocator_may_return_null=1:max_allocation_size_mb=" +
                        std::to_string(iso.max_memory >> 20) + ":hard_rss_limit_mb=" +
                        std::to_string((iso.max_memory >> 20) + 512));
  for (char** e = environ; *e; ++e)
    if (std::strncmp(*e, "ASAN_OPTIONS=", 13) != 0) env_strings.emplace_back(*e);
#else
  for (char** e = environ; *e; ++e) env_strings.emplace_back(*e);
#endif
  std::vector<char*> envp;
  for (auto& e : env_strings) envp.push_back(e.data());
  envp.push_back(nullptr);
  pid_t pid = -1;
  const int spawned = ::posix_spawn(&pid, iso.executable.c_str(), &actions, nullptr, argv.data(), envp.data());
  posix_spawn_file_actions_destroy(&actions);
  ::close(fds[1]);
  if (spawned != 0) {
    ::close(fds[0]);
    throw Error(ErrorCode::io_error, std::string("cannot start the Draco decoder: ") + std::strerror(spawned));
  }

  const auto deadline = Clock::now() + iso.deadline;
  std::vector<char> answer;
  const std::size_t cap = 20 + 12 * (3 * iso.max_triangles + 3) + 12 * iso.max_triangles;
  Transfer transfer = send_all(fds[0], data.data(), data.size(), deadline);
  ::shutdown(fds[0], SHUT_WR);
  if (transfer == Transfer::done) transfer = receive_all(fds[0], answer, cap, deadline);
  ::close(fds[0]);
  const bool complete = transfer == Transfer::done;
  if (!complete) ::kill(pid, SIGKILL);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (transfer == Transfer::timed_out) refuse("took longer than " + std::to_string(iso.deadline.count()) + " s");
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || !complete) refuse(describe_end(status, iso));
  return parse_answer(answer, iso.max_triangles);
}

int decode_draco_child(int argc, char** argv) {
  if (argc != 5) return 2;
  const std::uint64_t max_triangles = std::strtoull(argv[2], nullptr, 10);
  const std::uint64_t max_memory = std::strtoull(argv[3], nullptr, 10);
  const rlim_t cpu = std::strtoull(argv[4], nullptr, 10);
#if !defined(__SANITIZE_ADDRESS__)
  const rlimit memory_limit{max_memory, max_memory};
  ::setrlimit(RLIMIT_DATA, &memory_limit);
#else
  // ASan's per-allocation cap (set by the parent) stops one huge
  // reservation; this stops many smaller ones: resident memory above what
  // the process started with plus the limit ends it, as the rlimit would.
  std::thread([max_memory] {
    const std::uint64_t start = resident_bytes();
    for (;;) {
      if (resident_bytes() > start + max_memory) ::kill(::getpid(), SIGKILL);
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }).detach();
#endif
  const rlimit cpu_limit{cpu, cpu + 1};  // SIGXCPU at the soft limit, SIGKILL a second later
  ::setrlimit(RLIMIT_CPU, &cpu_limit);
  const rlimit no_core{0, 0};
  ::setrlimit(RLIMIT_CORE, &no_core);

  std::vector<std::uint8_t> input;
  try {
    std::uint8_t buf[1 << 16];
    for (;;) {
      const ssize_t n = ::read(0, buf, sizeof buf);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) return 3;
      if (n == 0) break;
      input.insert(input.end(), buf, buf + n);
    }
    DecodeLimits limits;
    limits.max_bytes = input.size() + 1;
    limits.max_triangles = max_triangles;
    const Mesh mesh = decode_mesh_as(MeshFormat::draco, input, limits);
    const std::uint64_t counts[2] = {mesh.vertices.size(), mesh.triangles.size()};
    write_all_or_exit(1, kMeshTag, 4);
    write_all_or_exit(1, counts, sizeof counts);
    write_all_or_exit(1, mesh.vertices.data(), 12 * mesh.vertices.size());
    write_all_or_exit(1, mesh.triangles.data(), 12 * mesh.triangles.size());
    return 0;
  } catch (const Error& e) {
    const auto code = static_cast<std::uint32_t>(e.code());
    write_all_or_exit(1, kErrorTag, 4);
    write_all_or_exit(1, &code, 4);
    write_all_or_exit(1, e.what(), std::strlen(e.what()));
    return 0;
  } catch (const std::bad_alloc&) {
    const auto code = static_cast<std::uint32_t>(ErrorCode::malformed_input);
    const char message[] = "the Draco data needs more memory than its size can justify; the file is corrupt";
    write_all_or_exit(1, kErrorTag, 4);
    write_all_or_exit(1, &code, 4);
    write_all_or_exit(1, message, sizeof message - 1);
    return 0;
  }
}

}  // namespace voxd::server
