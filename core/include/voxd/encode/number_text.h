#pragma once
// Numbers in text (PNG tEXt, NRRD headers, canonical URL queries): the
// shortest decimal that reads back as the same double, so a value written by
// voxd parses back exactly and equal values always print alike.
#include <charconv>
#include <string>

namespace voxd {

inline std::string number_text(double x) {
  char buf[32];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, x);
  (void)ec;  // 32 characters always hold a double's shortest form
  return std::string(buf, end);
}

}  // namespace voxd
