#pragma once
// The web page's files (web/, and the npm modules it imports), assembled
// into the binary at build time (server/CMakeLists.txt): path under /ui/ ->
// bytes, as they are and compressed.
#include <cstddef>
#include <string_view>
#include <vector>

namespace voxd::server {

struct WebAsset {
  std::string_view path;   // "index.html", "js/app.js", "vendor/three.module.js"
  std::string_view bytes;
  // The same bytes compressed once at build time (server/web_build/):
  // Content-Encoding br and gzip.
  std::string_view br;
  std::string_view gzip;
};

const std::vector<WebAsset>& web_assets();

}  // namespace voxd::server
