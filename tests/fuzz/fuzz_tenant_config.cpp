// libFuzzer harness for the text the tenants feature takes from outside:
// the first byte picks the tenants file's parser (server/tenants/) or the
// callback URL parser (server/webhooks/webhook_url.h); the rest is the text.
// Invariants: the file's parser refuses only with std::invalid_argument; a
// URL that parses has a scheme, host, port and target a sender can use, and
// written back out it parses to the same.
#include <cstdint>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <string_view>

#include "server/tenants/tenant_directory.h"
#include "server/webhooks/webhook_url.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string_view text(reinterpret_cast<const char*>(data + 1), size - 1);
  if (data[0] % 2 == 0) {
    try {
      const voxd::server::TenantTable t = voxd::server::parse_tenant_table(text);
      for (const auto& [digest, index] : t.keys)
        if (digest.size() != 64 || index >= t.tenants.size()) std::abort();
    } catch (const std::invalid_argument&) {
    }
    return 0;
  }
  std::string why;
  const auto url = voxd::server::parse_webhook_url(text, &why);
  if (!url) {
    if (why.empty()) std::abort();  // a refusal always says why
    return 0;
  }
  if ((url->scheme != "http" && url->scheme != "https") || url->host.empty() || url->port < 1 || url->port > 65535 ||
      url->target.empty() || url->target[0] != '/')
    std::abort();
  for (const char c : url->host + url->target)
    if (static_cast<unsigned char>(c) <= 0x20 || static_cast<unsigned char>(c) >= 0x7f || c == '#') std::abort();
  for (const char c : url->host)
    if (c == '@' || c == '/' || c == '?') std::abort();
  const std::string host = url->host.find(':') != std::string::npos ? "[" + url->host + "]" : url->host;
  const auto again = voxd::server::parse_webhook_url(url->scheme + "://" + host + ":" + std::to_string(url->port) + url->target, &why);
  if (!again || again->host != url->host || again->port != url->port || again->target != url->target) std::abort();
  return 0;
}
