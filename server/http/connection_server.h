#pragma once
// The HTTP server's connection handling, over cpp-httplib's request parsing
// and routing. httplib gives each connection a thread from accept to close,
// with a read timeout that restarts on every byte: a client sending a header
// a byte at a time holds a thread for as long as it likes, and a few dozen
// such clients starve every route, the probes included. Here:
//   - a connection waits for its request head on one epoll thread (the gate),
//     never on an HTTP thread, within an overall header deadline, and goes
//     back there between keep-alive requests;
//   - an HTTP thread takes it only with a whole request head in hand, and
//     reads the body within a deadline that grows with a minimum rate;
//   - a request whose body was refused unread really closes its connection,
//     so the rest of that body is never parsed as further requests;
//   - past the queue of requests waiting for a thread, or the connection
//     limit, a client gets a 429 or 503 problem at once, not a reset; the
//     listen backlog is sized for bursts;
//   - a long-lived request (a server-sent event stream, open for as long as
//     its job runs) runs on a stream thread of its own, up to max_streams of
//     them, so that open streams never take the HTTP threads every other
//     request needs; past max_streams it gets a 503 at once.
// A handler reaches its own connection through the functions at the end.
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string_view>

#include <httplib.h>

namespace voxd::server {

struct ConnectionLimits {
  int threads = 16;                  // HTTP threads running requests
  std::size_t max_streams = 64;      // long-lived requests at once, each on a stream thread (503 above)
  std::size_t max_queued = 256;      // requests with a head, waiting for a thread (429 above)
  std::size_t max_connections = 1024;  // open connections (503 above)
  int backlog = 1024;                // listen backlog
  std::chrono::seconds header_timeout{10};  // from a request's first byte to the end of its head
  std::chrono::seconds body_grace{10};      // a body may take this long plus its bytes at...
  std::size_t body_min_rate = 16 * 1024;    // ...this many bytes a second
  std::chrono::seconds keep_alive_timeout{5};  // idle between requests
  int keep_alive_max_count = 1000;
  std::chrono::seconds read_timeout{30};   // one stalled read
  std::chrono::seconds write_timeout{30};  // one stalled write
};

class ConnectionServer : public httplib::Server {
 public:
  explicit ConnectionServer(ConnectionLimits limits);
  ~ConnectionServer() override;

  // After bind_to_port / bind_to_any_port: the backlog httplib leaves at 5.
  void apply_backlog();
  // After listen_after_bind returned: closes every connection, joins threads.
  void close_connections();
  // Which requests are long-lived, by their request line ("GET /path?q
  // HTTP/1.1"); set before listening.
  void set_stream_requests(std::function<bool(std::string_view request_line)> is_stream);

 private:
  bool process_and_close_socket(socket_t sock) override;

  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// For the handler running on this thread (no effect outside a request):
// the request head is done, its body is read from now on. Whatever part of
// the body the head announces (Content-Length, or any Transfer-Encoding) the
// answer leaves unread, the connection closes after it; and after a head
// whose length is ambiguous (two Content-Lengths, or one with a
// Transfer-Encoding: RFC 9112 6.3) in any case.
void begin_request_body(const httplib::Request& req);
// Whether this thread is one of the stream threads (a long-lived request).
bool on_stream_thread();
// The body was left unread: close the connection after the response.
void close_connection_after_response();
// Whether the client has closed or reset its side of the connection.
bool request_client_gone();

}  // namespace voxd::server
