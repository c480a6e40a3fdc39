#include "server/http/route_label.h"

#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "server/http/openapi_document.h"

namespace voxd::server {
namespace {

std::vector<std::string_view> segments_of(std::string_view path) {
  std::vector<std::string_view> out;
  std::size_t start = 1;  // after the leading '/'
  while (start <= path.size()) {
    const std::size_t end = std::min(path.find('/', start), path.size());
    out.push_back(path.substr(start, end - start));
    start = end + 1;
  }
  return out;
}

bool is_parameter(std::string_view segment) {
  return segment.size() > 2 && segment.front() == '{' && segment.back() == '}';
}

struct Template {
  std::string text;
  std::vector<std::string> segments;
};

const std::vector<Template>& documented_paths() {
  static const std::vector<Template> templates = [] {
    std::vector<Template> out;
    const nlohmann::json document = nlohmann::json::parse(served_openapi_document());
    for (const auto& [path, item] : document.at("paths").items()) {
      Template t{path, {}};
      for (auto s : segments_of(path)) t.segments.emplace_back(s);
      out.push_back(std::move(t));
    }
    return out;
  }();
  return templates;
}

// A parameter matches one non-empty segment; "{file}" (the web page's files
// under /ui/, which have folders) matches the rest of the path.
bool matches(const Template& t, const std::vector<std::string_view>& path) {
  for (std::size_t i = 0; i < t.segments.size(); ++i) {
    if (i >= path.size()) return false;
    const std::string& s = t.segments[i];
    if (s == "{file}" && i + 1 == t.segments.size()) return !path[i].empty();
    if (is_parameter(s) ? path[i].empty() : s != path[i]) return false;
  }
  return t.segments.size() == path.size();
}

}  // namespace

void prepare_route_labels() { documented_paths(); }

std::string route_label(const std::string& path) {
  const auto segments = segments_of(path);
  for (const Template& t : documented_paths())
    if (matches(t, segments)) return t.text;
  return "other";
}

}  // namespace voxd::server
