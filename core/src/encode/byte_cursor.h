#pragma once
// Bounds-checked reading of untrusted bytes. Every read names what it is
// reading, so running out of data or a bad varint becomes a voxd::Error that
// tells the user what was cut short and where.
#include <cstdint>
#include <span>
#include <string>

#include "voxd/error.h"

namespace voxd::encode {

class ByteCursor {
 public:
  // `on_exhausted` is the error for reading past the end: truncated_input for
  // a whole stream, malformed_input for a block whose declared length is too
  // short for its content. `context` prefixes every message. `base_offset` is
  // where `data` starts in the whole input, so messages give absolute offsets.
  ByteCursor(std::span<const std::uint8_t> data, ErrorCode on_exhausted, std::string context,
             std::size_t base_offset = 0)
      : data_(data), on_exhausted_(on_exhausted), context_(std::move(context)), base_(base_offset) {}

  std::size_t offset() const { return base_ + pos_; }  // absolute, for messages
  std::size_t remaining() const { return data_.size() - pos_; }
  bool at_end() const { return pos_ == data_.size(); }

  std::uint8_t u8(const char* what) {
    if (remaining() < 1) exhausted(what);
    return data_[pos_++];
  }

  std::uint32_t u32le(const char* what) {
    if (remaining() < 4) exhausted(what);
    std::uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v |= static_cast<std::uint32_t>(data_[pos_ + i]) << (8 * i);
    pos_ += 4;
    return v;
  }

  // Unsigned LEB128, at most 10 bytes, value below 2^64.
  std::uint64_t varint(const char* what) {
    const std::size_t start = offset();
    std::uint64_t v = 0;
    for (int shift = 0; shift < 70; shift += 7) {
      if (at_end()) exhausted(what);
      const std::uint8_t b = data_[pos_++];
      if (shift == 63 && b > 1)
        fail(ErrorCode::malformed_input, std::string(what) + " at byte " + std::to_string(start) +
                                             " is a varint larger than 2^64 - 1");
      v |= static_cast<std::uint64_t>(b & 0x7f) << shift;
      if ((b & 0x80) == 0) return v;
    }
    fail(ErrorCode::malformed_input,
         std::string(what) + " at byte " + std::to_string(start) + " is a varint longer than 10 bytes");
  }

  std::span<const std::uint8_t> bytes(std::uint64_t n, const char* what) {
    if (n > remaining()) exhausted(what);
    auto s = data_.subspan(pos_, static_cast<std::size_t>(n));
    pos_ += static_cast<std::size_t>(n);
    return s;
  }

  [[noreturn]] void fail(ErrorCode code, const std::string& message) const {
    throw Error(code, context_ + ": " + message);
  }

 private:
  [[noreturn]] void exhausted(const char* what) const {
    fail(on_exhausted_, "data ends inside " + std::string(what) + " at byte " + std::to_string(offset()));
  }

  std::span<const std::uint8_t> data_;
  std::size_t pos_ = 0;
  ErrorCode on_exhausted_;
  std::string context_;
  std::size_t base_;
};

}  // namespace voxd::encode
