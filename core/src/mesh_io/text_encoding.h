#pragma once
// Text in UTF-16, as Windows tools save it ("Unicode" in Notepad): known by
// its byte order mark and decoded to UTF-8 before the text formats read it,
// as their keywords and numbers are ASCII.
#include <cstdint>
#include <optional>
#include <span>
#include <string>

namespace voxd::mesh_io {

enum class Utf16Order { little_endian, big_endian };

// The byte order its mark says, when `data` starts with one.
std::optional<Utf16Order> utf16_byte_order(std::span<const std::uint8_t> data);

// The text after the byte order mark as UTF-8. Throws Error
// (malformed_input) on an odd byte count or an unpaired surrogate, naming
// the byte offset.
std::string utf16_to_utf8(std::span<const std::uint8_t> data, Utf16Order order);

}  // namespace voxd::mesh_io
