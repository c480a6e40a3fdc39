#include "api/param_validator.h"
#include "voxd/encode/number_text.h"

#include <array>

namespace voxd::api {

using nlohmann::json;

std::optional<Rgba8> ParamValidator::color(const json& v, const std::string& path) {
  const std::string hint = "must be a colour: [r, g, b], [r, g, b, a] (integers 0 to 255) or \"#rrggbb\" / \"#rrggbbaa\"";
  std::array<int, 4> c{0, 0, 0, 255};
  if (v.is_array() && (v.size() == 3 || v.size() == 4)) {
    for (std::size_t i = 0; i < v.size(); ++i) {
      const auto x = integer_value(v[i], path + "/" + std::to_string(i), 0, 255);
      if (!x) return std::nullopt;
      c[i] = static_cast<int>(*x);
    }
  } else if (v.is_string() && (v.get<std::string>().size() == 7 || v.get<std::string>().size() == 9) &&
             v.get<std::string>()[0] == '#' &&
             v.get<std::string>().find_first_not_of("0123456789abcdefABCDEF", 1) == std::string::npos) {
    const std::string h = v.get<std::string>();
    for (std::size_t i = 0; 1 + 2 * i < h.size(); ++i)
      c[i] = parse_number<int>(std::string_view(h).substr(1 + 2 * i, 2), 16).value();  // two hex digits, checked above
  } else {
    fail(path, hint + ", got " + brief_json(v));
    return std::nullopt;
  }
  if (c[3] == 0) {
    fail(path, "alpha 0 marks empty voxels; give a colour with alpha 1 to 255");
    return std::nullopt;
  }
  return Rgba8{static_cast<std::uint8_t>(c[0]), static_cast<std::uint8_t>(c[1]), static_cast<std::uint8_t>(c[2]),
               static_cast<std::uint8_t>(c[3])};
}

std::optional<std::vector<Rgba8>> ParamValidator::colors(const json& obj, const std::string& path, const char* key,
                                                         std::size_t lo, std::size_t hi) {
  if (!obj.contains(key)) return std::nullopt;
  const json& v = obj.at(key);
  const std::string p = path + "/" + key;
  if (!v.is_array() || v.size() < lo || v.size() > hi) {
    fail(p, "must be an array of " + (lo == hi ? std::to_string(lo) : std::to_string(lo) + " to " + std::to_string(hi)) +
                    " colours");
    return std::nullopt;
  }
  std::vector<Rgba8> out;
  for (std::size_t i = 0; i < v.size(); ++i) {
    const auto c = color(v[i], p + "/" + std::to_string(i));
    if (!c) return std::nullopt;
    out.push_back(*c);
  }
  return out;
}

std::optional<std::uint64_t> ParamValidator::seed(const json& obj, const std::string& path) {
  if (!obj.contains("seed")) return std::nullopt;
  const json& v = obj.at("seed");
  if (!v.is_number_integer() || (!v.is_number_unsigned() && v.get<std::int64_t>() < 0)) {
    fail(path + "/seed", "must be a non-negative integer, got " + brief_json(v));
    return std::nullopt;
  }
  return v.get<std::uint64_t>();
}

}  // namespace voxd::api
