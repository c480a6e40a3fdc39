#pragma once
// Numbers in text, both ways, one rule each for the whole code base.
//  - number_text: the shortest decimal that reads back as the same double
//    (PNG tEXt, NRRD headers, canonical URL queries), so a value written by
//    voxd parses back exactly and equal values always print alike.
//  - parse_number: the whole text as a number of type T, or nothing. Plain
//    decimal only: no leading space or '+', no trailing characters, no
//    wrap-around of "-1" into an unsigned type, no value out of T's range.
//    Callers say what range they accept and how to word a refusal.
#include <charconv>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>

namespace voxd {

inline std::string number_text(double x) {
  char buf[32];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, x);
  (void)ec;  // 32 characters always hold a double's shortest form
  return std::string(buf, end);
}

// `base` applies to integers (16 for a colour's hex digits).
template <typename T>
std::optional<T> parse_number(std::string_view text, int base = 10) {
  static_assert(std::is_arithmetic_v<T> && !std::is_same_v<T, bool>);
  T value{};
  const char* const end = text.data() + text.size();
  std::from_chars_result r;
  if constexpr (std::is_integral_v<T>) r = std::from_chars(text.data(), end, value, base);
  else r = std::from_chars(text.data(), end, value);
  if (text.empty() || r.ec != std::errc() || r.ptr != end) return std::nullopt;
  return value;
}

}  // namespace voxd
