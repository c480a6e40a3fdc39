#include "api/bounded_json.h"

namespace voxd::api {
namespace {

// The deepest nesting of arrays and objects in the text, stopping as soon as
// it passes `limit` (strings and their escapes are skipped, so brackets
// inside them do not count). Malformed text is left to the parser.
int nesting_depth(std::string_view text, int limit) {
  int depth = 0, deepest = 0;
  bool in_string = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\') ++i;
      else if (c == '"') in_string = false;
      continue;
    }
    if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      deepest = std::max(deepest, ++depth);
      if (deepest > limit) return deepest;
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return deepest;
}

}  // namespace

nlohmann::json parse_bounded_json(std::string_view text, std::string_view what, const JsonLimits& limits) {
  const std::string name(what);
  if (text.size() > limits.max_bytes)
    throw InvalidJson(InvalidJson::Reason::too_large,
                      name + " is " + std::to_string(text.size()) + " bytes of JSON, over the limit of " +
                          std::to_string(limits.max_bytes) + " bytes");
  if (nesting_depth(text, limits.max_depth) > limits.max_depth)
    throw InvalidJson(InvalidJson::Reason::too_deep, name + " nests arrays and objects more than " +
                                                         std::to_string(limits.max_depth) +
                                                         " levels deep; job parameters need 5 at most");
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    // parse_error, and out_of_range for numbers beyond a double (1e400).
    throw InvalidJson(InvalidJson::Reason::malformed, name + " is not valid JSON: " + e.what());
  }
}

std::string brief_json(const nlohmann::json& value) {
  switch (value.type()) {
    case nlohmann::json::value_t::array: return "an array of " + std::to_string(value.size()) + " items";
    case nlohmann::json::value_t::object: return "an object of " + std::to_string(value.size()) + " fields";
    case nlohmann::json::value_t::string: {
      constexpr std::size_t kShown = 40;
      const auto& s = value.get_ref<const std::string&>();
      if (s.size() <= kShown) return value.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
      return nlohmann::json(s.substr(0, kShown)).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) +
             "... (" + std::to_string(s.size()) + " characters)";
    }
    default: return value.dump();
  }
}

}  // namespace voxd::api
