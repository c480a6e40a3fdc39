#pragma once
// Registers routes on the HTTP server the one way every route is registered:
// each handler guarded (an exception becomes a problem+json answer, counted
// by its problem type, never a crash), and, once all are in, a 405 with Allow
// for the methods a known path does not take (not a misleading 404).
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace httplib {
class Server;
struct Request;
struct Response;
class ContentReader;
}  // namespace httplib

namespace voxd::server {

class Metrics;

using Handler = std::function<void(const httplib::Request&, httplib::Response&)>;
// An upload handler reads the request body itself, as it arrives.
using UploadHandler = std::function<void(const httplib::Request&, httplib::Response&, const httplib::ContentReader&)>;

// Only registers: the handlers it installs do not refer to it.
class RouteTable {
 public:
  RouteTable(httplib::Server& server, Metrics& metrics) : server_(server), metrics_(metrics) {}

  void get(const std::string& pattern, Handler handler);
  void del(const std::string& pattern, Handler handler);
  void post_upload(const std::string& pattern, UploadHandler handler);

  // Answers every method a registered pattern does not take with 405 and its
  // Allow list. Call once, after the last route.
  void refuse_other_methods();

 private:
  void note(const std::string& pattern, const char* method);
  Handler guarded(Handler handler) const;

  httplib::Server& server_;
  Metrics& metrics_;
  std::vector<std::string> patterns_;  // in registration order
  std::map<std::string, std::vector<std::string>> methods_;
};

// An upload handler that read the whole body says so: an error answer can then
// keep the connection open. Otherwise the unread rest of the body must never be
// read as further requests, and the connection closes after the answer.
void set_body_consumed(bool consumed);

}  // namespace voxd::server
