#pragma once
// Text from a request (a path, a client's X-Request-Id, a mesh file's words
// quoted in an error) on its way into a log line: control characters and
// non-ASCII bytes are written as \xHH, so a client cannot end a log line,
// forge the next one or send terminal escapes to whoever reads the log.
#include <string>
#include <string_view>

namespace voxd::server {

inline std::string log_safe(std::string_view text) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  out.reserve(text.size());
  for (const char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    if (c >= 0x20 && c < 0x7f && c != '\\') {
      out += ch;
    } else {
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 15];
    }
  }
  return out;
}

// A client's X-Request-Id kept for correlation if it is a plain token of at
// most 128 characters ([A-Za-z0-9._:+/=-], what UUIDs, trace ids and base64
// use); anything else is replaced by a fresh id.
inline bool is_plain_request_id(std::string_view id) {
  if (id.empty() || id.size() > 128) return false;
  for (const char c : id) {
    const bool plain = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' ||
                       c == '_' || c == ':' || c == '+' || c == '/' || c == '=' || c == '-';
    if (!plain) return false;
  }
  return true;
}

}  // namespace voxd::server
