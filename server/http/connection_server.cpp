#include "server/http/connection_server.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cctype>
#include <charconv>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <mutex>
#include <string>
#include <string_view>
#include <thread>
#include <unordered_map>
#include <vector>

#include <spdlog/spdlog.h>

namespace voxd::server {
namespace {

using Clock = std::chrono::steady_clock;

int remaining_ms(Clock::time_point deadline, std::chrono::seconds cap) {
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
  return static_cast<int>(std::clamp<long long>(left, 0, std::chrono::milliseconds(cap).count()));
}

// One client connection: its socket and what has been read ahead of the
// request being parsed (httplib reads request lines a byte at a time).
class Connection final : public httplib::Stream {
 public:
  Connection(int fd, const ConnectionLimits& limits) : fd_(fd), limits_(limits) {}
  ~Connection() override {
    ::shutdown(fd_, SHUT_RDWR);
    ::close(fd_);
  }

  // Reads of the request head must end by `deadline`.
  void begin_head(Clock::time_point deadline) {
    deadline_ = deadline;
    in_body_ = false;
    close_after_ = false;
    status_ = 0;
  }
  // `announced` is what the head says the body holds: its Content-Length (0
  // without one), or for a chunked body at least its last chunk's 5 bytes.
  void begin_body(std::uint64_t content_length, bool chunked) {
    in_body_ = true;
    body_start_ = Clock::now();
    body_bytes_ = 0;
    body_announced_ = chunked ? kChunkedEnd : content_length;
    update_body_deadline();
  }
  void close_after() { close_after_ = true; }
  // Closing is a must when the answer left the body (or some of it) unread:
  // what is left would otherwise be parsed as the next request. This holds
  // for every early answer (a 401, a preflight, a 413, a refused part) without
  // each having to remember it, and for a request httplib answered itself
  // before the body's start was known (a 400 or 414 on a broken head).
  // And an error answer to a request with a body closes it too: httplib
  // answers 400 when it cannot read a body (a broken chunk) and leaves the
  // rest where the next request would be parsed from.
  bool must_close() const {
    return close_after_ || !in_body_ || body_bytes_ < body_announced_ || (body_announced_ > 0 && status_ >= 400);
  }
  bool has_buffered() const { return pos_ < len_; }
  std::string_view buffered() const { return {buffer_.data() + pos_, len_ - pos_}; }
  int fd() const { return fd_; }

  bool peer_gone() const {
    pollfd p{fd_, POLLIN | POLLRDHUP, 0};
    if (::poll(&p, 1, 0) <= 0) return false;
    if (p.revents & (POLLRDHUP | POLLHUP | POLLERR)) return true;
    char c;
    return ::recv(fd_, &c, 1, MSG_PEEK | MSG_DONTWAIT) == 0;
  }

  bool is_readable() const override { return has_buffered() || wait(POLLIN, read_wait_ms()); }
  bool is_writable() const override { return wait(POLLOUT, limits_.write_timeout.count() * 1000); }

  ssize_t read(char* ptr, size_t size) override {
    if (!has_buffered()) {
      if (!wait(POLLIN, read_wait_ms())) return -1;
      const ssize_t n = ::recv(fd_, buffer_.data(), buffer_.size(), 0);
      if (n <= 0) return n;
      pos_ = 0;
      len_ = static_cast<std::size_t>(n);
    }
    const std::size_t n = std::min(size, len_ - pos_);
    std::memcpy(ptr, buffer_.data() + pos_, n);
    pos_ += n;
    if (in_body_) {
      body_bytes_ += n;
      update_body_deadline();
    }
    return static_cast<ssize_t>(n);
  }

  ssize_t write(const char* ptr, size_t size) override {
    // The status of the answer, from its status line (httplib writes the
    // head in one piece; a 100 Continue comes first and is not final).
    if (status_ < 200 && size >= 12 && std::string_view(ptr, 9) == "HTTP/1.1 ")
      status_ = (ptr[9] - '0') * 100 + (ptr[10] - '0') * 10 + (ptr[11] - '0');
    std::size_t done = 0;
    while (done < size) {
      if (!wait(POLLOUT, limits_.write_timeout.count() * 1000)) return done ? static_cast<ssize_t>(done) : -1;
      const ssize_t n = ::send(fd_, ptr + done, size - done, MSG_NOSIGNAL);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) return done ? static_cast<ssize_t>(done) : -1;
      done += static_cast<std::size_t>(n);
    }
    return static_cast<ssize_t>(done);
  }

  void get_remote_ip_and_port(std::string& ip, int& port) const override { address(true, ip, port); }
  void get_local_ip_and_port(std::string& ip, int& port) const override { address(false, ip, port); }
  socket_t socket() const override { return fd_; }

 private:
  void update_body_deadline() {
    const auto allowed = limits_.body_grace + std::chrono::seconds(body_bytes_ / std::max<std::size_t>(1, limits_.body_min_rate));
    deadline_ = body_start_ + allowed;
  }
  int read_wait_ms() const { return remaining_ms(deadline_, limits_.read_timeout); }
  bool wait(short events, long long ms) const {
    pollfd p{fd_, events, 0};
    for (;;) {
      const int r = ::poll(&p, 1, static_cast<int>(ms));
      if (r < 0 && errno == EINTR) continue;
      return r > 0 && (p.revents & (events | POLLHUP | POLLERR));
    }
  }
  void address(bool remote, std::string& ip, int& port) const {
    sockaddr_storage addr{};
    socklen_t len = sizeof addr;
    const int r = remote ? ::getpeername(fd_, reinterpret_cast<sockaddr*>(&addr), &len)
                         : ::getsockname(fd_, reinterpret_cast<sockaddr*>(&addr), &len);
    if (r != 0) return;
    char text[INET6_ADDRSTRLEN] = {};
    if (addr.ss_family == AF_INET) {
      const auto* a = reinterpret_cast<const sockaddr_in*>(&addr);
      ::inet_ntop(AF_INET, &a->sin_addr, text, sizeof text);
      port = ntohs(a->sin_port);
    } else if (addr.ss_family == AF_INET6) {
      const auto* a = reinterpret_cast<const sockaddr_in6*>(&addr);
      ::inet_ntop(AF_INET6, &a->sin6_addr, text, sizeof text);
      port = ntohs(a->sin6_port);
    }
    ip = text;
  }

  int fd_;
  const ConnectionLimits& limits_;
  std::array<char, 4096> buffer_{};
  std::size_t pos_ = 0, len_ = 0;
  Clock::time_point deadline_ = Clock::now();
  static constexpr std::uint64_t kChunkedEnd = 5;  // "0\r\n\r\n"
  bool in_body_ = false;
  Clock::time_point body_start_;
  std::size_t body_bytes_ = 0;
  std::uint64_t body_announced_ = 0;
  int status_ = 0;  // of the answer being written (0 before its status line)
  bool close_after_ = false;
};

thread_local Connection* current_connection = nullptr;
thread_local bool on_stream_thread_flag = false;

// A whole problem response written straight to a socket that no HTTP thread
// serves (never blocks: what does not fit the socket buffer is dropped).
void send_canned(int fd, int status, const char* reason, const char* slug, const char* title, const char* detail,
                 bool retry_after) {
  const std::string body = std::string(R"({"type":"urn:voxd:problem:)") + slug + R"(","title":")" + title +
                           R"(","status":)" + std::to_string(status) + R"(,"detail":")" + detail + R"("})";
  std::string head = "HTTP/1.1 " + std::to_string(status) + " " + reason +
                     "\r\nContent-Type: application/problem+json\r\nConnection: close\r\n";
  if (retry_after) head += "Retry-After: 1\r\n";
  head += "Content-Length: " + std::to_string(body.size()) + "\r\n\r\n";
  const std::string all = head + body;
  [[maybe_unused]] const ssize_t n = ::send(fd, all.data(), all.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
}

// The end of a request head in what has arrived so far.
bool has_complete_head(std::string_view data) {
  return data.find("\r\n\r\n") != std::string_view::npos || data.find("\n\n") != std::string_view::npos;
}

bool is_token_char(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
         std::string_view("!#$%&'*+-.^_`|~").find(c) != std::string_view::npos;
}

bool equal_ignoring_case(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) == std::tolower(static_cast<unsigned char>(y));
         });
}

std::string_view trim_blanks(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

// Why a request head is not strict HTTP/1.1 (RFC 9112), or null when it is:
// lines end in CRLF; the request line is METHOD SP TARGET SP HTTP/1.x; each
// header line is a token, a colon, and a value without CR, LF or NUL (no
// line folding). `data` may go on past the head (a body, or a head cut by the
// peer's close: then it is incomplete, which httplib answers itself).
const char* head_syntax_error(std::string_view data) {
  std::size_t at = 0;
  bool first = true;
  int lengths = 0, codings = 0;
  for (;;) {
    const std::size_t lf = data.find('\n', at);
    if (lf == std::string_view::npos) return nullptr;  // cut short: httplib refuses it
    if (lf == at || data[lf - 1] != '\r') return "a line of the request head does not end in CRLF";
    const std::string_view line = data.substr(at, lf - 1 - at);
    at = lf + 1;
    if (line.find('\r') != std::string_view::npos || line.find('\0') != std::string_view::npos)
      return "a line of the request head holds a CR or NUL";
    if (first) {
      first = false;
      const std::size_t sp1 = line.find(' '), sp2 = line.rfind(' ');
      if (sp1 == std::string_view::npos || sp2 == sp1 || sp1 == 0 || sp2 == sp1 + 1 ||
          line.substr(sp2 + 1, 7) != "HTTP/1." || line.size() != sp2 + 9 ||
          !std::all_of(line.begin(), line.begin() + static_cast<std::ptrdiff_t>(sp1), is_token_char) ||
          line.substr(sp1 + 1, sp2 - sp1 - 1).find_first_of(" \t") != std::string_view::npos)
        return "the request line is not METHOD SP TARGET SP HTTP/1.1";
      // A path ("/..."), or "*" for OPTIONS: httplib takes the first
      // non-empty piece between '?'s for the path, so "?/v1/jobs/..." would
      // be routed as "/v1/jobs/..." where a proxy sees no such path.
      const std::string_view target = line.substr(sp1 + 1, sp2 - sp1 - 1);
      if (target.front() != '/' && target != "*") return "the request target is not a path starting with /";
      // A fragment is never sent (RFC 9112, 3.2: a path and a query only),
      // and httplib drops one before routing, where a proxy may not: the
      // same line would name two resources.
      if (target.find('#') != std::string_view::npos)
        return "the request target holds a fragment ('#'): send the path and query only";
      continue;
    }
    if (line.empty()) {  // the end of the head
      if (lengths > 1 || (lengths == 1 && codings > 0))
        return "the request gives its body's length twice (two Content-Length headers, or Content-Length with "
               "Transfer-Encoding): send one";
      return nullptr;
    }
    const std::size_t colon = line.find(':');
    if (colon == 0 || colon == std::string_view::npos ||
        !std::all_of(line.begin(), line.begin() + static_cast<std::ptrdiff_t>(colon), is_token_char))
      return "a header line is not NAME: VALUE (a token, then a colon; no space before it, no folding)";
    // The headers that frame the body are read one way only.
    const std::string_view name = line.substr(0, colon), value = trim_blanks(line.substr(colon + 1));
    if (equal_ignoring_case(name, "Content-Length")) {
      ++lengths;
      if (value.empty() || value.size() > 19 || !std::all_of(value.begin(), value.end(), [](char c) { return c >= '0' && c <= '9'; }))
        return "Content-Length is not a number of bytes";
    } else if (equal_ignoring_case(name, "Transfer-Encoding")) {
      ++codings;
      if (codings > 1 || !equal_ignoring_case(value, "chunked"))
        return "the only Transfer-Encoding this service reads is a single \"chunked\"";
    }
  }
}

}  // namespace

struct ConnectionServer::Impl {
  explicit Impl(ConnectionLimits l) : limits(l) {}

  ConnectionLimits limits;
  std::atomic<std::size_t> open{0};  // connections, anywhere
  std::function<bool(std::string_view)> is_stream;
  ConnectionServer* server = nullptr;

  // The gate: connections waiting for a request head, or lingering after a
  // refusal (reading what the client still sends, so closing with unread
  // data does not reset the connection before the client reads the answer).
  enum class Phase { idle, head, lingering };
  struct Waiting {
    std::unique_ptr<Connection> connection;
    Phase phase;
    Clock::time_point deadline;
    int served = 0;  // requests already answered on it
    std::size_t drained = 0;  // bytes read and dropped while lingering
  };
  int epoll_fd = -1, wake_fd = -1;
  std::mutex incoming_mutex;
  std::vector<Waiting> incoming;
  std::unordered_map<int, Waiting> waiting;  // gate thread only
  std::thread gate;

  // Requests with a head, for the HTTP threads.
  std::mutex queue_mutex;
  std::condition_variable queue_cv;
  std::deque<Waiting> queue;
  std::vector<std::thread> workers;
  bool stopping = false;

  // Long-lived requests, each on a stream thread: threads are made as
  // streams arrive (max_streams at most) and wait for the next one after.
  std::deque<Waiting> stream_queue;         // guarded by queue_mutex
  std::condition_variable stream_cv;
  std::vector<std::thread> stream_workers;  // guarded by queue_mutex
  std::size_t idle_stream_workers = 0;      // guarded by queue_mutex
  std::atomic<std::size_t> streams{0};      // running or waiting for a stream thread

  void start(ConnectionServer& owner) {
    server = &owner;
    epoll_fd = ::epoll_create1(EPOLL_CLOEXEC);
    wake_fd = ::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
    epoll_event ev{};
    ev.events = EPOLLIN;
    ev.data.fd = wake_fd;
    ::epoll_ctl(epoll_fd, EPOLL_CTL_ADD, wake_fd, &ev);
    gate = std::thread([this] { gate_loop(); });
    for (int i = 0; i < std::max(1, limits.threads); ++i) workers.emplace_back([this] { work(*server); });
  }

  void stop() {
    {
      std::lock_guard lock(queue_mutex);
      if (stopping) return;
      stopping = true;
    }
    queue_cv.notify_all();
    stream_cv.notify_all();
    wake();
    if (gate.joinable()) gate.join();
    for (auto& t : workers) t.join();
    workers.clear();
    // The gate is gone, so no stream thread is made from now on.
    for (auto& t : stream_workers) t.join();
    stream_workers.clear();
    stream_queue.clear();
    queue.clear();
    waiting.clear();
    incoming.clear();
    if (epoll_fd >= 0) ::close(epoll_fd);
    if (wake_fd >= 0) ::close(wake_fd);
    epoll_fd = wake_fd = -1;
  }

  void wake() const {
    const std::uint64_t one = 1;
    [[maybe_unused]] const ssize_t n = ::write(wake_fd, &one, sizeof one);
  }

  // Called on httplib's accept thread.
  void admit(int fd) {
    if (open.load() >= limits.max_connections) {
      send_canned(fd, 503, "Service Unavailable", "too-many-connections", "Too many connections",
                  "the service holds as many connections as it allows; retry shortly", true);
      ::shutdown(fd, SHUT_RDWR);
      ::close(fd);
      return;
    }
    ++open;
    to_gate({std::make_unique<Connection>(fd, limits), Phase::idle, Clock::now() + limits.header_timeout, 0});
  }

  void to_gate(Waiting w) {
    {
      std::lock_guard lock(incoming_mutex);
      incoming.push_back(std::move(w));
    }
    wake();
  }

  void close_connection(Waiting& w) {
    w.connection.reset();
    --open;
  }

  void gate_loop() {
    std::array<epoll_event, 64> events;
    for (;;) {
      {
        std::lock_guard lock(queue_mutex);
        if (stopping) break;
      }
      Clock::time_point next = Clock::now() + std::chrono::seconds(1);
      for (const auto& [fd, w] : waiting) next = std::min(next, w.deadline);
      const int n = ::epoll_wait(epoll_fd, events.data(), static_cast<int>(events.size()),
                                 remaining_ms(next, std::chrono::seconds(1)) + 1);
      for (int i = 0; i < n; ++i) {
        const int fd = events[static_cast<std::size_t>(i)].data.fd;
        if (fd == wake_fd) {
          std::uint64_t count;
          [[maybe_unused]] const ssize_t r = ::read(wake_fd, &count, sizeof count);
          take_incoming();
          continue;
        }
        auto it = waiting.find(fd);
        if (it != waiting.end()) examine(it, (events[static_cast<std::size_t>(i)].events & (EPOLLRDHUP | EPOLLHUP)) != 0);
      }
      expire();
    }
    for (auto& [fd, w] : waiting) close_connection(w);
    waiting.clear();
    std::lock_guard lock(incoming_mutex);
    for (auto& w : incoming) close_connection(w);
    incoming.clear();
  }

  void take_incoming() {
    std::vector<Waiting> arrived;
    {
      std::lock_guard lock(incoming_mutex);
      arrived.swap(incoming);
    }
    for (auto& w : arrived) {
      const int fd = w.connection->fd();
      epoll_event ev{};
      // Edge-triggered: the head is only peeked at, so a level-triggered
      // descriptor would report the same bytes forever.
      ev.events = EPOLLIN | EPOLLRDHUP | EPOLLET;
      ev.data.fd = fd;
      if (::epoll_ctl(epoll_fd, EPOLL_CTL_ADD, fd, &ev) != 0) {
        close_connection(w);
        continue;
      }
      auto [it, inserted] = waiting.emplace(fd, std::move(w));
      // Data that came before the descriptor was added is reported on add,
      // but a head already buffered by the HTTP thread is not: look now.
      examine(it);
    }
  }

  void forget(std::unordered_map<int, Waiting>::iterator it) {
    ::epoll_ctl(epoll_fd, EPOLL_CTL_DEL, it->first, nullptr);
    waiting.erase(it);
  }

  // `hung_up`: the client has closed its side (what it sent is all there is).
  void examine(std::unordered_map<int, Waiting>::iterator it, bool hung_up = false) {
    Waiting& w = it->second;
    const int fd = it->first;
    if (w.phase == Phase::lingering) {
      std::array<char, 16384> sink;
      for (;;) {
        const ssize_t r = ::recv(fd, sink.data(), sink.size(), MSG_DONTWAIT);
        w.drained += r > 0 ? static_cast<std::size_t>(r) : 0;
        if (r > 0 && w.drained < kMaxDrained) continue;
        if (r < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)) return;
        close_connection(w);
        forget(it);
        return;
      }
    }
    // What the connection has read ahead (a pipelined request), then what
    // waits in the socket, peeked.
    std::string data(w.connection->buffered());
    std::array<char, 16384> head;
    const ssize_t r = ::recv(fd, head.data(), head.size(), MSG_PEEK | MSG_DONTWAIT);
    const bool failed = r < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR;
    if ((r == 0 || failed) && data.empty()) {
      close_connection(w);  // the client closed (or reset) its side
      forget(it);
      return;
    }
    if (r > 0) data.append(head.data(), static_cast<std::size_t>(r));
    if (data.empty()) return;
    if (w.phase == Phase::idle) {
      // The request's first byte starts its header deadline.
      w.phase = Phase::head;
      w.deadline = Clock::now() + limits.header_timeout;
    }
    // A head longer than the peek cannot be checked: 431. The client closing
    // its side after a whole head still gets its answer.
    const bool peer_done = r == 0 || failed || hung_up;
    const bool complete = has_complete_head(data);
    if (!complete && static_cast<std::size_t>(std::max<ssize_t>(r, 0)) == head.size()) {
      send_canned(fd, 431, "Request Header Fields Too Large", "header-too-large", "Request head too large",
                  "the request line and headers take more than 16 KiB; send a shorter head", false);
      return linger(it);
    }
    if (!complete && !peer_done) return;
    // Only a head every reader frames the same way goes to httplib, which is
    // lenient (it skips header lines it cannot read): a proxy in front could
    // frame such a head otherwise, and what one takes for a body the other
    // takes for a request.
    if (const char* why = head_syntax_error(data)) {
      send_canned(fd, 400, "Bad Request", "bad-request", "Bad request", why, false);
      return linger(it);
    }
    dispatch(it, is_stream && is_stream(std::string_view(data).substr(0, data.find_first_of("\r\n"))));
  }

  // After an answer that ends the connection while the client may still be
  // sending: closing with unread data would reset the connection, and the
  // client could lose the answer before reading it. The gate reads and drops
  // what comes for up to 2 s (kMaxDrained bytes at most), then closes.
  static constexpr std::size_t kMaxDrained = std::size_t{64} << 20;
  static void start_lingering(Waiting& w) {
    ::shutdown(w.connection->fd(), SHUT_WR);
    w.phase = Phase::lingering;
    w.deadline = Clock::now() + std::chrono::seconds(2);
  }
  void linger(std::unordered_map<int, Waiting>::iterator it) {
    start_lingering(it->second);
    examine(it);
  }

  void dispatch(std::unordered_map<int, Waiting>::iterator it, bool stream = false) {
    if (stream) return dispatch_stream(it);
    {
      std::lock_guard lock(queue_mutex);
      if (queue.size() < limits.max_queued) {
        ::epoll_ctl(epoll_fd, EPOLL_CTL_DEL, it->first, nullptr);
        it->second.connection->begin_head(it->second.deadline);
        queue.push_back(std::move(it->second));
        waiting.erase(it);
        queue_cv.notify_one();
        return;
      }
    }
    send_canned(it->first, 429, "Too Many Requests", "too-many-requests", "Too many requests",
                "every HTTP thread is busy and the queue of waiting requests is full; retry shortly", true);
    linger(it);
  }

  void dispatch_stream(std::unordered_map<int, Waiting>::iterator it) {
    {
      std::lock_guard lock(queue_mutex);
      if (!stopping && streams.load() < limits.max_streams) {
        ++streams;
        ::epoll_ctl(epoll_fd, EPOLL_CTL_DEL, it->first, nullptr);
        it->second.connection->begin_head(it->second.deadline);
        stream_queue.push_back(std::move(it->second));
        waiting.erase(it);
        // Each waiting stream needs an idle thread of its own: a woken thread
        // counts as idle until it runs, so in a burst the idle count alone
        // would send many streams to one thread.
        if (stream_queue.size() > idle_stream_workers) {
          stream_workers.emplace_back([this] { work_streams(); });
        } else {
          stream_cv.notify_one();
        }
        return;
      }
    }
    send_canned(it->first, 503, "Service Unavailable", "too-many-streams", "Too many event streams",
                "the service holds as many event streams open as it allows; poll GET /v1/jobs/{id} or retry shortly",
                true);
    linger(it);
  }

  void work_streams() {
    on_stream_thread_flag = true;
    for (;;) {
      Waiting w;
      {
        std::unique_lock lock(queue_mutex);
        ++idle_stream_workers;
        stream_cv.wait(lock, [&] { return stopping || !stream_queue.empty(); });
        --idle_stream_workers;
        if (stopping) return;
        w = std::move(stream_queue.front());
        stream_queue.pop_front();
      }
      serve(*server, w);
      --streams;
    }
  }

  void expire() {
    const auto now = Clock::now();
    for (auto it = waiting.begin(); it != waiting.end();) {
      auto current = it++;
      Waiting& w = current->second;
      if (w.deadline > now) continue;
      if (w.phase == Phase::head) {
        send_canned(current->first, 408, "Request Timeout", "request-timeout", "Request timeout",
                    "the request head did not arrive in time; send it whole", false);
        linger(current);
        continue;
      }
      close_connection(w);  // idle past keep-alive, or done lingering
      forget(current);
    }
  }

  void work(ConnectionServer& server) {
    for (;;) {
      Waiting w;
      {
        std::unique_lock lock(queue_mutex);
        queue_cv.wait(lock, [&] { return stopping || !queue.empty(); });
        if (stopping) return;
        w = std::move(queue.front());
        queue.pop_front();
      }
      serve(server, w);
    }
  }

  // Runs the request whose head is here, then hands the connection back to
  // the gate (or closes it). A pipelined request already read ahead goes
  // through the gate too, so it is classified like any other: an event
  // stream behind a plain request must get a stream thread, not keep this one.
  void serve(ConnectionServer& server, Waiting& w) {
    Connection& c = *w.connection;
    current_connection = &c;
    bool connection_closed = false;
    const bool last = w.served + 1 >= limits.keep_alive_max_count;
    bool ok = false;
    try {
      ok = server.process_request(c, last, connection_closed, nullptr);
    } catch (const std::exception& e) {
      spdlog::error("HTTP request processing failed: {}", e.what());
    }
    current_connection = nullptr;
    ++w.served;
    if (!ok) {
      close_connection(w);
      return;
    }
    if (c.must_close()) {  // a body left unread
      start_lingering(w);
      to_gate(std::move(w));
      return;
    }
    if (connection_closed || last) {
      close_connection(w);
      return;
    }
    if (c.has_buffered()) {
      w.phase = Phase::head;  // a pipelined request: its head deadline runs
      w.deadline = Clock::now() + limits.header_timeout;
    } else {
      w.phase = Phase::idle;
      w.deadline = Clock::now() + limits.keep_alive_timeout;
    }
    to_gate(std::move(w));
  }
};

ConnectionServer::ConnectionServer(ConnectionLimits limits) : impl_(std::make_unique<Impl>(limits)) {
  set_read_timeout(limits.read_timeout.count(), 0);
  set_write_timeout(limits.write_timeout.count(), 0);
  set_keep_alive_timeout(limits.keep_alive_timeout.count());
  set_keep_alive_max_count(static_cast<std::size_t>(limits.keep_alive_max_count));
  // The accept loop only hands sockets to the gate, which never blocks.
  struct Inline : httplib::TaskQueue {
    void enqueue(std::function<void()> fn) override { fn(); }
    void shutdown() override {}
  };
  new_task_queue = [] { return new Inline; };
  // httplib's default sets SO_REUSEPORT, so a second server (a mistaken
  // second start, or any process of the same user) binds the same port and
  // takes half the connections. SO_REUSEADDR alone lets a restart bind at
  // once past TIME_WAIT, and a port in use is an error.
  set_socket_options([](socket_t sock) {
    int yes = 1;
    ::setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  });
  impl_->start(*this);
}

ConnectionServer::~ConnectionServer() { close_connections(); }

void ConnectionServer::apply_backlog() {
  // Listening again on a listening socket changes its backlog (Linux).
  const socket_t sock = svr_sock_;
  if (sock != INVALID_SOCKET && ::listen(sock, impl_->limits.backlog) != 0)
    spdlog::warn("cannot raise the listen backlog to {}: {}", impl_->limits.backlog, std::strerror(errno));
}

void ConnectionServer::close_connections() { impl_->stop(); }

void ConnectionServer::set_stream_requests(std::function<bool(std::string_view)> is_stream) {
  impl_->is_stream = std::move(is_stream);
}

bool ConnectionServer::process_and_close_socket(socket_t sock) {
  impl_->admit(sock);
  return true;
}

namespace {
// Two Content-Lengths, or one beside a Transfer-Encoding (RFC 9112 6.3). The
// gate refuses such heads before httplib sees them; this holds for a head
// that reached httplib some other way.
bool ambiguous_body_length(const httplib::Request& req) {
  const std::size_t lengths = req.headers.count("Content-Length");
  return lengths > 1 || (lengths == 1 && req.has_header("Transfer-Encoding"));
}
}  // namespace

void begin_request_body(const httplib::Request& req) {
  if (!current_connection) return;
  // A length that is not plain digits is as good as unknown: whatever httplib
  // made of it, the connection is not trusted after the answer.
  std::uint64_t length = 0;
  if (req.has_header("Content-Length")) {
    const std::string text = req.get_header_value("Content-Length");
    const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), length);
    if (text.empty() || error != std::errc() || end != text.data() + text.size()) length = UINT64_MAX;
  }
  // Any Transfer-Encoding counts as a body, even one httplib does not read
  // (it reads only exactly "chunked"), so that one closes the connection too.
  current_connection->begin_body(length, req.has_header("Transfer-Encoding"));
  if (ambiguous_body_length(req)) current_connection->close_after();
}

bool on_stream_thread() { return on_stream_thread_flag; }

void close_connection_after_response() {
  if (current_connection) current_connection->close_after();
}

bool request_client_gone() { return current_connection && current_connection->peer_gone(); }

}  // namespace voxd::server
