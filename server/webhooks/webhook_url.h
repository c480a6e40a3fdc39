#pragma once
// A job's callback URL (webhooks), parsed strictly: http or https, a host
// (a name, an IPv4 address or a bracketed IPv6 one), an optional port, a
// path and query; no user info, no fragment. What the allow-list is checked
// against and what the sender connects to are this host and port, so the
// two can never disagree.
#include <optional>
#include <string>
#include <string_view>

namespace voxd::server {

struct WebhookUrl {
  std::string scheme;  // "http" | "https"
  std::string host;    // lowercase; an IPv6 address without its brackets
  int port = 0;        // explicit, or the scheme's
  std::string target;  // path and query, "/" at least
};

// Nothing, with `why` set, when the text is not such a URL.
std::optional<WebhookUrl> parse_webhook_url(std::string_view text, std::string* why);

}  // namespace voxd::server
