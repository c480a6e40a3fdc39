#pragma once
// An enum's names, written once: a table of (value, name) pairs from which its
// to_string, its parsing and the list of allowed names (in validators and
// error messages) all derive, so a name cannot be spelt two ways.
#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

namespace voxd {

template <typename E>
struct EnumName {
  E value;
  const char* name;
};

template <typename E, std::size_t N>
using EnumNames = std::array<EnumName<E>, N>;

template <typename E, std::size_t N>
constexpr const char* name_of(const EnumNames<E, N>& names, E value) noexcept {
  for (const EnumName<E>& n : names)
    if (n.value == value) return n.name;
  return "unknown";
}

template <typename E, std::size_t N>
constexpr std::optional<E> value_named(const EnumNames<E, N>& names, std::string_view name) noexcept {
  for (const EnumName<E>& n : names)
    if (name == n.name) return n.value;
  return std::nullopt;
}

// The names in table order, e.g. for a validator's list of allowed values.
template <typename E, std::size_t N>
constexpr std::array<std::string_view, N> names_in(const EnumNames<E, N>& names) noexcept {
  std::array<std::string_view, N> out{};
  for (std::size_t i = 0; i < N; ++i) out[i] = names[i].name;
  return out;
}

// "a, b, c", for messages.
template <typename E, std::size_t N>
std::string names_listed(const EnumNames<E, N>& names) {
  std::string out;
  for (const EnumName<E>& n : names) {
    if (!out.empty()) out += ", ";
    out += n.name;
  }
  return out;
}

// "a, b, c or d" (with last = " or "), or "a|b|c|d" (separator "|" and
// last "|"): the allowed names as messages and usage lines spell them.
template <typename E, std::size_t N>
std::string names_joined(const EnumNames<E, N>& names, std::string_view separator, std::string_view last) {
  std::string out;
  for (std::size_t i = 0; i < N; ++i) {
    if (i > 0) out += i + 1 == N ? last : separator;
    out += names[i].name;
  }
  return out;
}

}  // namespace voxd
