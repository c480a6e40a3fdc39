#pragma once
// Line and token scanning for the text formats (ASCII STL, OBJ, ASCII PLY).
// Lines are counted from 1 so error messages can point at them; "\n", "\r\n"
// and a lone "\r" all end a line.
#include <charconv>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string_view>
#include "voxd/encode/number_text.h"

namespace voxd::mesh_io {

class TextLines {
 public:
  explicit TextLines(std::string_view text) : text_(text) {
    // A UTF-8 byte order mark is not part of the first keyword.
    if (text_.starts_with("\xEF\xBB\xBF")) pos_ = 3;
    find_newline();
  }

  // Moves to the next line; false at the end of the text.
  bool next_line() {
    if (pos_ >= text_.size()) return false;
    // The next '\n' is remembered, so a file with lone '\r' line ends does not
    // rescan the rest of the text for every line.
    if (newline_ < pos_) find_newline();
    const char* base = text_.data();
    std::size_t end = newline_;
    if (const auto* cr = static_cast<const char*>(std::memchr(base + pos_, '\r', end - pos_)))
      end = static_cast<std::size_t>(cr - base);
    line_ = text_.substr(pos_, end - pos_);
    pos_ = end;
    if (pos_ < text_.size()) pos_ += (text_[pos_] == '\r' && pos_ + 1 < text_.size() && text_[pos_ + 1] == '\n') ? 2 : 1;
    ++line_number_;
    return true;
  }

  // Next whitespace-separated token of the current line; empty when none is left.
  std::string_view next_token() {
    std::size_t i = 0;
    while (i < line_.size() && is_blank(line_[i])) ++i;
    std::size_t j = i;
    while (j < line_.size() && !is_blank(line_[j])) ++j;
    const std::string_view token = line_.substr(i, j - i);
    line_.remove_prefix(j);
    return token;
  }

  void skip_rest_of_line() { line_ = {}; }
  std::size_t line_number() const { return line_number_; }
  // Bytes not yet scanned, the rest of the current line included.
  std::size_t remaining_bytes() const { return line_.size() + (text_.size() - pos_); }
  // Offset of the first byte after the current line and its terminator.
  std::size_t next_line_offset() const { return pos_; }

 private:
  void find_newline() {
    if (pos_ >= text_.size()) {
      newline_ = text_.size();
      return;
    }
    const auto* found = static_cast<const char*>(std::memchr(text_.data() + pos_, '\n', text_.size() - pos_));
    newline_ = found ? static_cast<std::size_t>(found - text_.data()) : text_.size();
  }

  static bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\v' || c == '\f'; }

  std::string_view text_;
  std::size_t pos_ = 0;
  std::size_t newline_ = 0;
  std::string_view line_;
  std::size_t line_number_ = 0;
};

namespace detail {

inline std::string_view without_plus_sign(std::string_view token) {
  if (token.size() > 1 && token[0] == '+' && token[1] != '-') token.remove_prefix(1);
  return token;
}

// Narrowing a double beyond float range is undefined behaviour, so saturate
// to infinity (which callers reject as non-finite).
inline float narrow_to_float(double value) {
  constexpr double max = std::numeric_limits<float>::max();
  if (value > max) return std::numeric_limits<float>::infinity();
  if (value < -max) return -std::numeric_limits<float>::infinity();
  return static_cast<float>(value);  // NaN stays NaN; tiny values round to 0
}

// For a number even a double cannot hold: from_chars reports overflow and
// underflow alike, so tell them apart from the text.
inline float beyond_double(std::string_view token) {
  const bool negative = token[0] == '-';
  const std::string_view digits = negative ? token.substr(1) : token;
  const std::size_t e = digits.find_first_of("eE");
  const bool tiny = e != std::string_view::npos ? (e + 1 < digits.size() && digits[e + 1] == '-')
                                                : (digits.starts_with('0') || digits.starts_with('.'));
  const float magnitude = tiny ? 0.0f : std::numeric_limits<float>::infinity();
  return negative ? -magnitude : magnitude;
}

}  // namespace detail

// Parses a whole token as double-typed data (a PLY "double" property),
// narrowed to float. False when the token is not a number.
inline bool parse_double_as_float(std::string_view token, float& out) {
  token = detail::without_plus_sign(token);
  if (token.empty()) return false;
  double value = 0.0;
  const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (ptr != token.data() + token.size()) return false;
  if (ec == std::errc()) out = detail::narrow_to_float(value);
  else if (ec == std::errc::result_out_of_range) out = detail::beyond_double(token);
  else return false;
  return true;
}

// Parses a whole token as a coordinate, rounding once, straight to float.
// Values beyond float range become infinite (and are rejected as non-finite
// by the caller), values too small for float become zero.
inline bool parse_float(std::string_view token, float& out) {
  token = detail::without_plus_sign(token);
  if (token.empty()) return false;
  const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), out);
  if (ptr != token.data() + token.size()) return false;
  if (ec == std::errc()) return true;
  // from_chars leaves `out` alone when out of float range.
  return ec == std::errc::result_out_of_range && parse_double_as_float(token, out);
}

// ASCII case-insensitive comparison, for keywords some exporters upper-case.
inline bool equals_ignoring_case(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  const auto lower = [](char c) { return (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c; };
  for (std::size_t i = 0; i < a.size(); ++i)
    if (lower(a[i]) != lower(b[i])) return false;
  return true;
}

// Parses a whole token as a decimal integer (an optional sign allowed).
inline bool parse_integer(std::string_view token, std::int64_t& out) {
  const std::optional<std::int64_t> n = parse_number<std::int64_t>(detail::without_plus_sign(token));
  if (n) out = *n;
  return n.has_value();
}

}  // namespace voxd::mesh_io
