#include "server/http/route_table.h"

#include <algorithm>

#include <httplib.h>

#include "server/http/connection_server.h"
#include "server/http/metrics.h"
#include "server/http/problem.h"

namespace voxd::server {
namespace {

thread_local bool body_consumed = false;

// Call inside a catch block.
void answer_exception(const httplib::Request& req, httplib::Response& res, Metrics& metrics) {
  const Problem p = problem_from_current_exception();
  // Rejections are counted by their problem type, the same words clients see.
  if ((p.status >= 400 && p.status < 500) || p.status == 503) metrics.count_rejected(p.slug);
  send_problem(res, p, req.path);
}

}  // namespace

void set_body_consumed(bool consumed) { body_consumed = consumed; }

void RouteTable::note(const std::string& pattern, const char* method) {
  if (std::find(patterns_.begin(), patterns_.end(), pattern) == patterns_.end()) patterns_.push_back(pattern);
  methods_[pattern].push_back(method);
}

void RouteTable::get(const std::string& pattern, Handler handler) {
  note(pattern, "GET");
  server_.Get(pattern, guarded(std::move(handler)));
}

void RouteTable::del(const std::string& pattern, Handler handler) {
  note(pattern, "DELETE");
  server_.Delete(pattern, guarded(std::move(handler)));
}

httplib::Server::Handler RouteTable::guarded(Handler handler) const {
  return [&metrics = metrics_, handler = std::move(handler)](const httplib::Request& req, httplib::Response& res) {
    try {
      handler(req, res);
    } catch (...) {
      answer_exception(req, res, metrics);
    }
  };
}

void RouteTable::post_upload(const std::string& pattern, UploadHandler handler) {
  note(pattern, "POST");
  server_.Post(pattern, [&metrics = metrics_, handler = std::move(handler)](const httplib::Request& req, httplib::Response& res,
                                                             const httplib::ContentReader& reader) {
    body_consumed = false;
    try {
      handler(req, res, reader);
    } catch (...) {
      if (!body_consumed) {
        res.set_header("Connection", "close");
        close_connection_after_response();
      }
      answer_exception(req, res, metrics);
    }
  });
}

void RouteTable::refuse_other_methods() {
  for (const std::string& pattern : patterns_) {
    const std::vector<std::string>& taken = methods_.at(pattern);
    auto takes = [&](const char* m) { return std::find(taken.begin(), taken.end(), m) != taken.end(); };
    std::string allow;
    for (const char* m : {"GET", "POST", "DELETE"})
      if (takes(m)) {
        if (!allow.empty()) allow += ", ";
        allow += m;
      }
    auto refuse = [allow](const httplib::Request& req, httplib::Response& res) {
      res.set_header("Allow", allow);
      send_problem(res, make_problem(405, "method-not-allowed", "Method not allowed",
                                     req.method + " is not allowed on " + req.path + "; allowed: " + allow),
                   req.path);
    };
    if (!takes("GET")) server_.Get(pattern, refuse);
    if (!takes("POST")) server_.Post(pattern, refuse);
    if (!takes("DELETE")) server_.Delete(pattern, refuse);
    server_.Put(pattern, refuse);
    server_.Patch(pattern, refuse);
  }
}

}  // namespace voxd::server
