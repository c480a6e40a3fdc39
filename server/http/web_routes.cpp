#include "server/http/routes.h"

#include <openssl/evp.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <map>
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
  if (ends(".svg")) return "image/svg+xml";
  return "text/plain; charset=utf-8";
}

// A strong validator per file: the SHA-256 of its bytes, computed once for
// every file at the first request (a few milliseconds for all of them).
const std::string& etag_of(const WebAsset& asset) {
  static const std::map<const char*, std::string> etags = [] {
    std::map<const char*, std::string> out;
    for (const WebAsset& a : web_assets()) {
      unsigned char digest[EVP_MAX_MD_SIZE];
      unsigned int n = 0;
      EVP_Digest(a.bytes.data(), a.bytes.size(), digest, &n, EVP_sha256(), nullptr);
      static constexpr char kHex[] = "0123456789abcdef";
      std::string tag = "\"";
      for (unsigned int i = 0; i < 16 && i < n; ++i) {
        tag += kHex[digest[i] >> 4];
        tag += kHex[digest[i] & 15];
      }
      out[a.path.data()] = tag + "\"";
    }
    return out;
  }();
  return etags.at(asset.path.data());
}

// Whether Accept-Encoding takes `coding` (a token in the list whose q is not 0).
bool accepts(const std::string& accept_encoding, std::string_view coding) {
  std::size_t start = 0;
  while (start < accept_encoding.size()) {
    std::size_t end = accept_encoding.find(',', start);
    if (end == std::string::npos) end = accept_encoding.size();
    std::string item = accept_encoding.substr(start, end - start);
    start = end + 1;
    const std::size_t semi = item.find(';');
    std::string token = item.substr(0, semi);
    token.erase(0, token.find_first_not_of(" \t"));
    token.erase(token.find_last_not_of(" \t") + 1);
    for (char& c : token) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (token != coding) continue;
    if (semi == std::string::npos) return true;
    const std::string params = item.substr(semi + 1);
    const std::size_t q = params.find("q=");
    return q == std::string::npos || std::strtod(params.c_str() + q + 2, nullptr) > 0.0;
  }
  return false;
}

void answer_asset(const WebAsset& asset, const httplib::Request& req, httplib::Response& res) {
  // The page and the binary change together: a browser asks again each time
  // (no-cache), and a file it has gets 304 with no body (its ETag), so a
  // second load moves headers only.
  const std::string& etag = etag_of(asset);
  res.set_header("Cache-Control", "no-cache");
  res.set_header("ETag", etag);
  res.set_header("Vary", "Accept-Encoding");
  res.set_header("X-Content-Type-Options", "nosniff");
  if (req.get_header_value("If-None-Match") == etag) {
    res.status = 304;
    return;
  }
  // Compressed at build time; sent through a content provider of known
  // length, which httplib never compresses again (it would, per request,
  // a body set with set_content).
  std::string_view body = asset.bytes;
  const std::string accept = req.get_header_value("Accept-Encoding");
  if (!asset.br.empty() && asset.br.size() < body.size() && accepts(accept, "br")) {
    body = asset.br;
    res.set_header("Content-Encoding", "br");
  } else if (!asset.gzip.empty() && asset.gzip.size() < body.size() && accepts(accept, "gzip")) {
    body = asset.gzip;
    res.set_header("Content-Encoding", "gzip");
  }
  res.set_content_provider(body.size(), content_type_of(asset.path),
                           [body](std::size_t offset, std::size_t length, httplib::DataSink& sink) {
                             return sink.write(body.data() + offset, std::min(length, body.size() - offset));
                           });
}

const WebAsset* find_asset(std::string_view path) {
  for (const WebAsset& a : web_assets())
    if (a.path == path) return &a;
  return nullptr;
}

}  // namespace

void install_web_routes(RouteTable& routes) {
  routes.get("/", [](const httplib::Request& req, httplib::Response& res) {
    const WebAsset* index = find_asset("index.html");
    if (!index) throw ProblemError(make_problem(404, "not-found", "Not found", "this build has no web page"));
    answer_asset(*index, req, res);
  });
  // Browsers ask for it whatever the page links: the page's icon.
  routes.get("/favicon.ico", [](const httplib::Request& req, httplib::Response& res) {
    const WebAsset* icon = find_asset("favicon.svg");
    if (!icon) throw ProblemError(make_problem(404, "not-found", "Not found", "this build has no icon"));
    answer_asset(*icon, req, res);
  });
  // The API reference: Redoc over this service's own /openapi.json.
  routes.get("/docs", [](const httplib::Request& req, httplib::Response& res) {
    const WebAsset* page = find_asset("docs.html");
    if (!page) throw ProblemError(make_problem(404, "not-found", "Not found", "this build has no API reference page"));
    // Redoc would show its maker's logo from cdn.redoc.ly: the reference
    // asks this service for everything, or nothing (the image hides itself).
    res.set_header("Content-Security-Policy",
                   "default-src 'self'; img-src 'self' data:; style-src 'self' 'unsafe-inline'; "
                   "font-src 'self' data:; worker-src 'self' blob:; object-src 'none'; base-uri 'none'");
    answer_asset(*page, req, res);
  });
  routes.get(R"(/ui/([A-Za-z0-9._/-]+))", [](const httplib::Request& req, httplib::Response& res) {
    const std::string path = req.matches[1];
    const WebAsset* asset = find_asset(path);
    if (!asset)
      throw ProblemError(make_problem(404, "not-found", "Not found", "the web page has no file " + path));
    answer_asset(*asset, req, res);
  });
}

}  // namespace voxd::server
