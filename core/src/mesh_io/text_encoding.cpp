#include "mesh_io/text_encoding.h"

#include "voxd/error.h"

namespace voxd::mesh_io {
namespace {

[[noreturn]] void fail(std::size_t offset, const std::string& what) {
  throw Error(ErrorCode::malformed_input, "the file is UTF-16 text, broken at byte " + std::to_string(offset) + ": " +
                                              what + "; save it as UTF-8 (or ASCII)");
}

void append_utf8(std::string& out, std::uint32_t c) {
  if (c < 0x80) {
    out.push_back(static_cast<char>(c));
  } else if (c < 0x800) {
    out.push_back(static_cast<char>(0xC0 | (c >> 6)));
    out.push_back(static_cast<char>(0x80 | (c & 0x3F)));
  } else if (c < 0x10000) {
    out.push_back(static_cast<char>(0xE0 | (c >> 12)));
    out.push_back(static_cast<char>(0x80 | ((c >> 6) & 0x3F)));
    out.push_back(static_cast<char>(0x80 | (c & 0x3F)));
  } else {
    out.push_back(static_cast<char>(0xF0 | (c >> 18)));
    out.push_back(static_cast<char>(0x80 | ((c >> 12) & 0x3F)));
    out.push_back(static_cast<char>(0x80 | ((c >> 6) & 0x3F)));
    out.push_back(static_cast<char>(0x80 | (c & 0x3F)));
  }
}

}  // namespace

std::optional<Utf16Order> utf16_byte_order(std::span<const std::uint8_t> data) {
  if (data.size() < 2) return std::nullopt;
  if (data[0] == 0xFF && data[1] == 0xFE) return Utf16Order::little_endian;
  if (data[0] == 0xFE && data[1] == 0xFF) return Utf16Order::big_endian;
  return std::nullopt;
}

std::string utf16_to_utf8(std::span<const std::uint8_t> data, Utf16Order order) {
  if (data.size() % 2 != 0) fail(data.size() - 1, "an odd number of bytes");
  const bool big = order == Utf16Order::big_endian;
  auto unit = [&](std::size_t i) {
    return static_cast<std::uint32_t>(big ? (data[i] << 8) | data[i + 1] : (data[i + 1] << 8) | data[i]);
  };
  std::string out;
  out.reserve(data.size() / 2);
  for (std::size_t i = 2; i < data.size(); i += 2) {  // past the byte order mark
    const std::uint32_t u = unit(i);
    if (u >= 0xDC00 && u <= 0xDFFF) fail(i, "a low surrogate without its high one");
    if (u < 0xD800 || u > 0xDBFF) {
      append_utf8(out, u);
      continue;
    }
    if (i + 2 >= data.size()) fail(i, "a high surrogate at the end");
    const std::uint32_t low = unit(i + 2);
    if (low < 0xDC00 || low > 0xDFFF) fail(i + 2, "a high surrogate without its low one");
    append_utf8(out, 0x10000 + ((u - 0xD800) << 10) + (low - 0xDC00));
    i += 2;
  }
  return out;
}

}  // namespace voxd::mesh_io
