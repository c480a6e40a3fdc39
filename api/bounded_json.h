#pragma once
// Untrusted JSON text (job parameters from a request or a file) parsed with
// bounds. nlohmann's document takes about 26 times the text in memory, and
// its dump(), copies and comparisons recurse once per nesting level, so an
// unbounded document exhausts the memory or the stack before any validation
// runs. These bounds are checked on the text, before a document is built.
#include <cstddef>
#include <stdexcept>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace voxd::api {

struct JsonLimits {
  // Job parameters hold custom palettes and 3D colour lookups (64^3 cells at
  // most, ~12 bytes a colour): 8 MiB leaves room for those and no more.
  std::size_t max_bytes = std::size_t{8} << 20;
  // Job parameters nest 5 levels; 32 is room for any honest document.
  int max_depth = 32;
};

class InvalidJson : public std::runtime_error {
 public:
  enum class Reason { malformed, too_large, too_deep };
  InvalidJson(Reason reason, const std::string& message) : std::runtime_error(message), reason_(reason) {}
  Reason reason() const noexcept { return reason_; }

 private:
  Reason reason_;
};

// `what` names the text in messages, e.g. "params" or "--params".
// Throws InvalidJson; never lets a json::exception through.
nlohmann::json parse_bounded_json(std::string_view text, std::string_view what, const JsonLimits& limits = {});

// A value as it may appear in an error message: numbers, booleans and null in
// full, strings cut to a few dozen characters, arrays and objects by their
// kind and size only (never serialized: they may be huge or deep).
std::string brief_json(const nlohmann::json& value);

}  // namespace voxd::api
