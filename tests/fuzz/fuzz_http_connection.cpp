// libFuzzer harness for the HTTP edge (server/http/connection_server.h): each
// input is the raw bytes a client sends on one connection, to a real
// ConnectionServer on loopback with voxd's kinds of routes: probes, a /v1
// route behind an API key that refuses before reading the body, a preflight,
// a route that reads the body, and an event stream. After each input:
//   - nothing inside a body is parsed as a request: the server answers the
//     canary route no more often than an independent, strict framer
//     (below) finds it at a request's start (issue #37, finding 1);
//   - every event stream runs on a stream thread, never an HTTP thread,
//     however its request line is written (finding 2);
//   - never more responses than requests the strict framer found, plus one
//     (the answer to the request that broke its framing);
//   - and ASan/UBSan: no crash, no leak, no undefined behaviour.
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cstdint>
#include <cstdio>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <regex>
#include <string>
#include <string_view>
#include <thread>

#include <httplib.h>

#include "server/http/connection_server.h"
#include "server/http/stream_requests.h"

namespace {

using voxd::server::ConnectionServer;

std::atomic<int> canary_hits{0};
std::atomic<int> streams_on_http_threads{0};
int server_port = 0;

const std::string kJob(32, 'a');

void start_server() {
  static std::unique_ptr<ConnectionServer> server;
  voxd::server::ConnectionLimits limits;
  limits.threads = 2;
  limits.max_streams = 4;
  limits.header_timeout = std::chrono::seconds(1);
  limits.body_grace = std::chrono::seconds(1);
  limits.keep_alive_timeout = std::chrono::seconds(1);
  limits.read_timeout = std::chrono::seconds(1);
  limits.write_timeout = std::chrono::seconds(1);
  server = std::make_unique<ConnectionServer>(limits);
  server->set_stream_requests(voxd::server::is_event_stream_request);
  server->set_payload_max_length(1 << 16);
  server->set_pre_routing_handler([](const httplib::Request& req, httplib::Response& res) {
    voxd::server::begin_request_body(req);
    if (req.method == "OPTIONS" && req.has_header("Origin") && req.has_header("Access-Control-Request-Method")) {
      res.status = 204;
      return httplib::Server::HandlerResponse::Handled;
    }
    if (req.path.rfind("/v1/", 0) == 0 && req.get_header_value("Authorization") != "Bearer key") {
      res.status = 401;
      res.set_content("{}", "application/problem+json");
      return httplib::Server::HandlerResponse::Handled;
    }
    return httplib::Server::HandlerResponse::Unhandled;
  });
  server->Get("/healthz", [](const httplib::Request&, httplib::Response& res) { res.set_content("ok", "text/plain"); });
  server->Get("/canary", [](const httplib::Request&, httplib::Response& res) {
    ++canary_hits;
    res.set_content("canary", "text/plain");
  });
  server->Post("/v1/jobs", [](const httplib::Request& req, httplib::Response& res) {
    res.set_content(std::to_string(req.body.size()), "text/plain");
  });
  server->Get(R"(/v1/jobs/([0-9a-f]{32})/events)", [](const httplib::Request&, httplib::Response& res) {
    if (!voxd::server::on_stream_thread()) ++streams_on_http_threads;
    res.set_chunked_content_provider("text/event-stream", [](std::size_t, httplib::DataSink& sink) {
      sink.write("event: end\ndata: {}\n\n", 21);
      sink.done();
      return true;
    });
  });
  server_port = server->bind_to_any_port("127.0.0.1");
  if (server_port <= 0) std::abort();
  server->apply_backlog();
  std::thread([] { server->listen_after_bind(); }).detach();
}

// A strict reading of HTTP/1.1 framing (RFC 9112): request line and header
// lines end in CRLF, a body has one Content-Length of digits, or
// Transfer-Encoding exactly "chunked" with hex chunk sizes. It stops at the
// first thing it cannot frame for sure, or at "Connection: close". Counts
// the requests it framed and those of them that ask for the canary.
struct Framing {
  int requests = 0;
  int canaries = 0;
};

bool read_line(std::string_view data, std::size_t& at, std::string_view& line) {
  const std::size_t end = data.find("\r\n", at);
  if (end == std::string_view::npos) return false;
  line = data.substr(at, end - at);
  at = end + 2;
  return line.find('\n') == std::string_view::npos && line.find('\r') == std::string_view::npos;
}

bool lower_equal(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) == std::tolower(static_cast<unsigned char>(y));
         });
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

Framing frame(std::string_view data) {
  Framing f;
  std::size_t at = 0;
  while (at < data.size()) {
    std::string_view line;
    if (!read_line(data, at, line)) return f;
    if (line.empty()) continue;  // blank lines between requests are skipped by httplib, too
    const std::size_t sp1 = line.find(' '), sp2 = line.rfind(' ');
    if (sp1 == std::string_view::npos || sp2 == sp1) return f;
    const std::string_view method = line.substr(0, sp1), target = line.substr(sp1 + 1, sp2 - sp1 - 1);
    std::uint64_t length = 0;
    int lengths = 0;
    bool chunked = false, coded = false, close = false;
    for (;;) {
      if (!read_line(data, at, line)) return f;  // a head cut short: nothing after it is a request
      if (line.empty()) break;
      const std::size_t colon = line.find(':');
      if (colon == std::string_view::npos) return f;
      const std::string_view name = line.substr(0, colon), value = trim(line.substr(colon + 1));
      if (lower_equal(name, "content-length")) {
        ++lengths;
        if (value.empty() || value.size() > 12 || !std::all_of(value.begin(), value.end(), ::isdigit)) return f;
        length = std::stoull(std::string(value));
      } else if (lower_equal(name, "transfer-encoding")) {
        coded = true;
        chunked = lower_equal(value, "chunked");
      } else if (lower_equal(name, "connection") && lower_equal(value, "close")) {
        close = true;
      }
    }
    ++f.requests;
    // Whatever the method: a GET with a body has one, too.
    if (method == "GET" && (target == "/canary" || target.rfind("/canary?", 0) == 0)) ++f.canaries;
    if (lengths > 1 || (lengths == 1 && coded) || (coded && !chunked) || close) return f;
    if (chunked) {
      for (;;) {
        if (!read_line(data, at, line)) return f;
        const std::string_view size_text = line.substr(0, line.find(';'));
        if (size_text.empty() || size_text.size() > 8 || !std::all_of(size_text.begin(), size_text.end(), ::isxdigit))
          return f;
        const std::uint64_t size = std::stoull(std::string(size_text), nullptr, 16);
        if (size == 0) {
          if (!read_line(data, at, line) || !line.empty()) return f;  // no trailers
          break;
        }
        if (data.size() - at < size + 2 || data.substr(at + size, 2) != "\r\n") return f;
        at += size + 2;
      }
    } else {
      if (data.size() - at < length) return f;
      at += length;
    }
  }
  return f;
}

// Sends the input on a fresh connection and reads until the server closes.
std::string exchange(const std::uint8_t* data, std::size_t size) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<std::uint16_t>(server_port));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  // Tens of thousands of connections a minute can run short of loopback
  // ports for a moment (TIME_WAIT): retried, then a clear failure.
  for (int attempt = 0; ::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0; ++attempt) {
    if (attempt == 200) {
      std::fprintf(stderr, "cannot connect to the server: %s\n", std::strerror(errno));
      std::abort();
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  std::size_t sent = 0;
  while (sent < size) {
    const ssize_t n = ::send(fd, data + sent, size - sent, MSG_NOSIGNAL);
    if (n <= 0) break;  // the server closed: what it answered is read below
    sent += static_cast<std::size_t>(n);
  }
  ::shutdown(fd, SHUT_WR);
  std::string answer;
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(until - std::chrono::steady_clock::now());
    pollfd p{fd, POLLIN, 0};
    if (left.count() <= 0 || ::poll(&p, 1, static_cast<int>(left.count())) <= 0) break;
    char buf[65536];
    const ssize_t n = ::recv(fd, buf, sizeof buf, 0);
    if (n <= 0) break;
    answer.append(buf, static_cast<std::size_t>(n));
  }
  ::close(fd);
  return answer;
}

int count_responses(const std::string& bytes) {
  static const std::regex status_line("HTTP/1\\.1 [2-5][0-9][0-9] ");  // final answers, not 100 Continue
  return static_cast<int>(std::distance(std::sregex_iterator(bytes.begin(), bytes.end(), status_line), std::sregex_iterator()));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const bool started = (start_server(), true);
  (void)started;
  const int canaries_before = canary_hits.load();
  const std::string answer = exchange(data, size);
  const int canaries = canary_hits.load() - canaries_before;
  const Framing f = frame(std::string_view(reinterpret_cast<const char*>(data), size));
  if (std::getenv("VOXD_FUZZ_VERBOSE")) std::fprintf(stderr, "framed %d, canaries %d/%d, answer:\n%s\n", f.requests, canaries, f.canaries, answer.c_str());
  if (canaries > f.canaries) {
    std::fprintf(stderr, "a request was parsed out of a body: %d canary answers, %d framed\n", canaries, f.canaries);
    __builtin_trap();
  }
  if (streams_on_http_threads.load() > 0) {
    std::fprintf(stderr, "an event stream ran on an HTTP thread\n");
    __builtin_trap();
  }
  // Bodies are not scanned for status lines: responses' bodies here never
  // hold one (the routes answer short fixed texts).
  if (count_responses(answer) > f.requests + 1) {
    std::fprintf(stderr, "%d responses to %d framed requests\n", count_responses(answer), f.requests);
    __builtin_trap();
  }
  return 0;
}
