#pragma once
// The signature on a callback (X-Voxd-Signature), as Stripe-style receivers
// check it: "t=<unix seconds>,v1=<hex HMAC-SHA256(secret, "<t>.<body>")>".
// The time is signed with the body so that a captured callback cannot be
// replayed later; receivers refuse one whose t is too old (docs/security.md
// shows the check).
#include <cstdint>
#include <string>
#include <string_view>

namespace voxd::server {

std::string hmac_sha256_hex(std::string_view secret, std::string_view message);
std::string webhook_signature(std::string_view secret, std::int64_t unix_seconds, std::string_view body);

}  // namespace voxd::server
