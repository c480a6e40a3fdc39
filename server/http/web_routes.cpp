#include "server/http/routes.h"

#include <string>
#include <string_view>

#include <httplib.h>

#include "server/http/problem.h"
#include "server/http/route_table.h"
#include "server/http/web_assets.h"

namespace voxd::server {
namespace {

std::string content_type_of(std::string_view path) {
  auto ends = [&](std::string_view ext) { return path.size() >= ext.size() && path.substr(path.size() - ext.size()) == ext; };
  if (ends(".html")) return "text/html; charset=utf-8";
  if (ends(".js")) return "text/javascript; charset=utf-8";
  if (ends(".css")) return "text/css; charset=utf-8";
  if (ends(".json")) return "application/json";
  return "text/plain; charset=utf-8";
}

void answer_asset(const WebAsset& asset, httplib::Response& res) {
  // The page and the binary change together: a browser asks again (and gets
  // 200 from memory) rather than keep a page older than the API it calls.
  res.set_header("Cache-Control", "no-cache");
  res.set_header("X-Content-Type-Options", "nosniff");
  res.set_content(std::string(asset.bytes), content_type_of(asset.path));
}

const WebAsset* find_asset(std::string_view path) {
  for (const WebAsset& a : web_assets())
    if (a.path == path) return &a;
  return nullptr;
}

}  // namespace

void install_web_routes(RouteTable& routes) {
  routes.get("/", [](const httplib::Request&, httplib::Response& res) {
    const WebAsset* index = find_asset("index.html");
    if (!index) throw ProblemError(make_problem(404, "not-found", "Not found", "this build has no web page"));
    answer_asset(*index, res);
  });
  // The API reference: Redoc over this service's own /openapi.json.
  routes.get("/docs", [](const httplib::Request&, httplib::Response& res) {
    const WebAsset* page = find_asset("docs.html");
    if (!page) throw ProblemError(make_problem(404, "not-found", "Not found", "this build has no API reference page"));
    // Redoc would show its maker's logo from cdn.redoc.ly: the reference
    // asks this service for everything, or nothing (the image hides itself).
    res.set_header("Content-Security-Policy",
                   "default-src 'self'; img-src 'self' data:; style-src 'self' 'unsafe-inline'; "
                   "font-src 'self' data:; worker-src 'self' blob:; object-src 'none'; base-uri 'none'");
    answer_asset(*page, res);
  });
  routes.get(R"(/ui/([A-Za-z0-9._/-]+))", [](const httplib::Request& req, httplib::Response& res) {
    const std::string path = req.matches[1];
    const WebAsset* asset = find_asset(path);
    if (!asset)
      throw ProblemError(make_problem(404, "not-found", "Not found", "the web page has no file " + path));
    answer_asset(*asset, res);
  });
}

}  // namespace voxd::server
