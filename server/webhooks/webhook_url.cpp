#include "server/webhooks/webhook_url.h"

#include <algorithm>
#include <cctype>

#include "voxd/encode/number_text.h"

namespace voxd::server {
namespace {

bool host_char(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '.' || c == '_'; }

}  // namespace

std::optional<WebhookUrl> parse_webhook_url(std::string_view text, std::string* why) {
  auto fail = [&](const std::string& reason) -> std::optional<WebhookUrl> {
    if (why) *why = reason;
    return std::nullopt;
  };
  if (text.size() > 2048) return fail("the URL is over 2048 characters");
  for (const char c : text) {
    if (static_cast<unsigned char>(c) <= 0x20 || c == 0x7f) return fail("the URL has spaces or control characters");
    if (static_cast<unsigned char>(c) >= 0x80) return fail("the URL must be ASCII: percent-encode other characters");
  }
  WebhookUrl url;
  const std::size_t colon = text.find("://");
  if (colon == std::string_view::npos) return fail("it is not an absolute http:// or https:// URL");
  std::string scheme(text.substr(0, colon));
  std::transform(scheme.begin(), scheme.end(), scheme.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (scheme != "http" && scheme != "https") return fail("its scheme must be http or https");
  url.scheme = scheme;
  std::string_view rest = text.substr(colon + 3);
  if (rest.find('#') != std::string_view::npos) return fail("a callback URL has no fragment (#)");
  const std::size_t end = rest.find_first_of("/?");
  const std::string_view authority = rest.substr(0, end);
  url.target = end == std::string_view::npos ? "/" : std::string(rest.substr(end));
  if (url.target[0] == '?') url.target = "/" + url.target;
  if (authority.find('@') != std::string_view::npos) return fail("a callback URL carries no user name or password");
  std::string_view host = authority, port;
  bool has_port = false;
  if (!authority.empty() && authority[0] == '[') {
    const std::size_t close = authority.find(']');
    if (close == std::string_view::npos) return fail("its IPv6 address has no closing ]");
    host = authority.substr(1, close - 1);
    const std::string_view after = authority.substr(close + 1);
    if (!after.empty() && after[0] != ':') return fail("the host is malformed");
    if (!after.empty()) {
      port = after.substr(1);
      has_port = true;
    }
    if (host.empty() || !std::all_of(host.begin(), host.end(), [](char c) { return std::isxdigit(static_cast<unsigned char>(c)) || c == ':' || c == '.'; }))
      return fail("its IPv6 address is malformed");
  } else {
    const std::size_t p = authority.rfind(':');
    if (p != std::string_view::npos) {
      host = authority.substr(0, p);
      port = authority.substr(p + 1);
      has_port = true;
    }
    if (host.empty() || !std::all_of(host.begin(), host.end(), host_char)) return fail("its host is empty or malformed");
  }
  url.host = std::string(host);
  std::transform(url.host.begin(), url.host.end(), url.host.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (has_port) {
    const auto n = parse_number<int>(std::string(port));
    if (!n || *n < 1 || *n > 65535) return fail("its port must be 1 to 65535");
    url.port = *n;
  } else {
    url.port = url.scheme == "https" ? 443 : 80;
  }
  return url;
}

}  // namespace voxd::server
