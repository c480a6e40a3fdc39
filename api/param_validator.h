#pragma once
// The job JSON's validation: every problem is collected with its JSON path
// instead of stopping at the first one, so a client fixes all of them in one
// round trip. The job parameters (api/job_params.cpp) and every mode's
// options (api/modes/) are read through it, so a number, a choice or a colour
// is checked, and its error worded, the same way everywhere.
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <glm/vec3.hpp>
#include <nlohmann/json.hpp>

#include "api/bounded_json.h"
#include "api/param_error.h"
#include "voxd/dense_volume.h"
#include "voxd/enum_names.h"

namespace voxd::api {

class ParamValidator {
 public:
  std::vector<FieldError> errors;

  static std::string type_name(const nlohmann::json& v) { return v.type_name(); }

  void fail(const std::string& path, const std::string& message) { errors.push_back({path, message}); }

  bool is_object(const nlohmann::json& v, const std::string& path) {
    if (v.is_object()) return true;
    fail(path, "must be an object, got " + type_name(v));
    return false;
  }

  void allow_keys(const nlohmann::json& obj, const std::string& path, std::initializer_list<std::string_view> keys) {
    allow_keys(obj, path, std::span<const std::string_view>(keys.begin(), keys.size()));
  }
  void allow_keys(const nlohmann::json& obj, const std::string& path, std::span<const std::string_view> keys) {
    for (const auto& [key, value] : obj.items()) {
      bool known = false;
      for (auto k : keys) known = known || key == k;
      if (!known) {
        std::string list;
        for (auto k : keys) list += (list.empty() ? "" : ", ") + std::string(k);
        fail(path + "/" + key, "unknown field; allowed here: " + list);
      }
    }
  }

  std::optional<double> number(const nlohmann::json& obj, const std::string& path, const char* key, double lo, double hi,
                               bool lo_exclusive) {
    if (!obj.contains(key)) return std::nullopt;
    const nlohmann::json& v = obj.at(key);
    const std::string p = path + "/" + key;
    if (!v.is_number()) {
      fail(p, "must be a number, got " + type_name(v));
      return std::nullopt;
    }
    const double d = v.get<double>();
    if (!std::isfinite(d) || (lo_exclusive ? d <= lo : d < lo) || d > hi) {
      fail(p, "must be " + std::string(lo_exclusive ? "> " : ">= ") + fmt(lo) + " and <= " + fmt(hi) + ", got " + brief_json(v));
      return std::nullopt;
    }
    return d;
  }

  std::optional<std::int64_t> integer(const nlohmann::json& obj, const std::string& path, const char* key, std::int64_t lo,
                                      std::int64_t hi) {
    if (!obj.contains(key)) return std::nullopt;
    return integer_value(obj.at(key), path + "/" + key, lo, hi);
  }

  std::optional<std::int64_t> integer_value(const nlohmann::json& v, const std::string& p, std::int64_t lo, std::int64_t hi) {
    if (!v.is_number_integer()) {
      fail(p, "must be an integer, got " + (v.is_number() ? brief_json(v) : type_name(v)));
      return std::nullopt;
    }
    const auto i = v.get<std::int64_t>();
    if (v.is_number_unsigned() && v.get<std::uint64_t>() > static_cast<std::uint64_t>(hi)) {
      fail(p, "must be between " + std::to_string(lo) + " and " + std::to_string(hi) + ", got " + brief_json(v));
      return std::nullopt;
    }
    if (i < lo || i > hi) {
      fail(p, "must be between " + std::to_string(lo) + " and " + std::to_string(hi) + ", got " + brief_json(v));
      return std::nullopt;
    }
    return i;
  }

  std::optional<std::string> one_of(const nlohmann::json& obj, const std::string& path, const char* key,
                                    std::initializer_list<std::string_view> allowed) {
    return one_of(obj, path, key, std::span<const std::string_view>(allowed.begin(), allowed.size()));
  }
  std::optional<std::string> one_of(const nlohmann::json& obj, const std::string& path, const char* key,
                                    std::span<const std::string_view> allowed) {
    if (!obj.contains(key)) return std::nullopt;
    const nlohmann::json& v = obj.at(key);
    const std::string p = path + "/" + key;
    std::string list;
    for (auto a : allowed) list += (list.empty() ? "" : ", ") + std::string("\"") + std::string(a) + "\"";
    if (!v.is_string()) {
      fail(p, "must be one of " + list + ", got " + type_name(v));
      return std::nullopt;
    }
    const auto s = v.get<std::string>();
    for (auto a : allowed)
      if (s == a) return s;
    fail(p, "must be one of " + list + ", got " + brief_json(v));
    return std::nullopt;
  }

  // One of an enum's names (voxd/enum_names.h), as its value.
  template <typename E, std::size_t N>
  std::optional<E> one_of(const nlohmann::json& obj, const std::string& path, const char* key, const EnumNames<E, N>& names) {
    const std::array<std::string_view, N> allowed = names_in(names);
    const auto name = one_of(obj, path, key, std::span<const std::string_view>(allowed));
    return name ? value_named(names, *name) : std::nullopt;
  }

  std::optional<glm::dvec3> vec3(const nlohmann::json& obj, const std::string& path, const char* key) {
    if (!obj.contains(key)) return std::nullopt;
    const nlohmann::json& v = obj.at(key);
    const std::string p = path + "/" + key;
    if (!v.is_array() || v.size() != 3) {
      fail(p, "must be an array of 3 numbers");
      return std::nullopt;
    }
    glm::dvec3 out;
    bool ok = true;
    for (int i = 0; i < 3; ++i) {
      if (!v[i].is_number() || !std::isfinite(v[i].get<double>())) {
        fail(p + "/" + std::to_string(i), "must be a finite number, got " + brief_json(v[i]));
        ok = false;
      } else {
        out[i] = v[i].get<double>();
      }
    }
    return ok ? std::optional(out) : std::nullopt;
  }

  // A colour: [r, g, b] or [r, g, b, a] (0..255, alpha defaults to 255) or
  // "#rrggbb" / "#rrggbbaa". Alpha 0 is refused: it marks empty voxels.
  std::optional<Rgba8> color(const nlohmann::json& v, const std::string& path);
  // A list of `lo`..`hi` colours under obj[key].
  std::optional<std::vector<Rgba8>> colors(const nlohmann::json& obj, const std::string& path, const char* key,
                                           std::size_t lo, std::size_t hi);
  // A non-negative integer seed under obj["seed"].
  std::optional<std::uint64_t> seed(const nlohmann::json& obj, const std::string& path);

  static std::string fmt(double d) {
    nlohmann::json j = d;
    return j.dump();
  }
};


}  // namespace voxd::api
