#pragma once
// A plain TCP connection to a test server on loopback, for requests no HTTP
// client library would send: trickled heads, bodies that lie about their
// length, requests smuggled behind a refused body.
#include <chrono>
#include <string>

namespace voxd::test {

class RawSocket {
 public:
  explicit RawSocket(int port);  // throws when the connection fails
  ~RawSocket();
  RawSocket(const RawSocket&) = delete;
  RawSocket& operator=(const RawSocket&) = delete;

  // Sends all of `data`; false when the peer closed or reset meanwhile.
  bool send(const std::string& data);
  // Everything the server sends until it closes the connection, or until
  // `timeout` passes; `closed` says which.
  std::string read_until_closed(std::chrono::milliseconds timeout, bool* closed = nullptr);
  // Waits up to `timeout` for some bytes (or the close); returns them.
  std::string read_some(std::chrono::milliseconds timeout);
  void close();

 private:
  int fd_ = -1;
};

}  // namespace voxd::test
