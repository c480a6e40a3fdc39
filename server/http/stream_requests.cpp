#include "server/http/stream_requests.h"

#include <algorithm>
#include <string>
#include <vector>

#include <httplib.h>

namespace voxd::server {

bool is_event_stream_request(std::string_view request_line) {
  // Split as httplib splits it (on spaces, each word trimmed of spaces and
  // tabs, empty ones dropped), and decode the path as httplib does before
  // routing: the route is matched on what httplib makes of the line, so
  // "/v1/jobs/%61bc.../events" and ".../events#x" are streams too.
  std::vector<std::string_view> words;
  for (std::size_t start = 0; start < request_line.size() && words.size() < 3;) {
    const std::size_t end = std::min(request_line.find(' ', start), request_line.size());
    std::string_view word = request_line.substr(start, end - start);
    while (!word.empty() && (word.front() == ' ' || word.front() == '\t')) word.remove_prefix(1);
    while (!word.empty() && (word.back() == ' ' || word.back() == '\t')) word.remove_suffix(1);
    if (!word.empty()) words.push_back(word);
    start = end + 1;
  }
  // HEAD runs GET's handlers in httplib, without a body: never long-lived.
  if (words.size() < 2 || words[0] != "GET") return false;
  // httplib cuts the target at its query or fragment before decoding it.
  const std::string_view target = words[1].substr(0, words[1].find_first_of("?#"));
  const std::string path = httplib::detail::decode_url(std::string(target), false);
  constexpr std::string_view kJobs = "/v1/jobs/", kEvents = "/events";
  const std::string_view p = path;
  if (p.size() != kJobs.size() + 32 + kEvents.size() || p.substr(0, kJobs.size()) != kJobs ||
      p.substr(kJobs.size() + 32) != kEvents)
    return false;
  const std::string_view id = p.substr(kJobs.size(), 32);
  return std::all_of(id.begin(), id.end(), [](char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'); });
}

}  // namespace voxd::server
