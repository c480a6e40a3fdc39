#pragma once
// A window onto a ByteSource for parsers that need a few bytes ahead: the
// next n bytes as a span, then consumed. A source that is whole in memory is
// viewed where it lies; any other is buffered, holding no more than the
// largest piece asked for at once (one RLE slab block).
#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

#include "voxd/byte_source.h"

namespace voxd::encode {

class SourceWindow {
 public:
  explicit SourceWindow(ByteSource& source) : source_(source), whole_(source.whole()) {}

  // The next `n` bytes, or fewer when the source ends first.
  std::span<const std::uint8_t> peek(std::size_t n) {
    if (!whole_.empty()) {
      const std::size_t at = std::min(offset_, whole_.size());
      return whole_.subspan(at, std::min(n, whole_.size() - at));
    }
    if (buffer_.size() - at_ < n && !ended_) fill(n);
    return std::span<const std::uint8_t>(buffer_).subspan(at_, std::min(n, buffer_.size() - at_));
  }
  // Steps over `n` bytes peek() returned.
  void consume(std::size_t n) {
    offset_ += n;
    if (whole_.empty()) at_ += n;
  }
  // Whether the whole source is in memory (peeking far costs nothing).
  bool in_memory() const { return !whole_.empty(); }
  // Bytes consumed so far: where the window starts in the whole stream.
  std::size_t offset() const { return offset_; }

 private:
  void fill(std::size_t n) {
    buffer_.erase(buffer_.begin(), buffer_.begin() + static_cast<std::ptrdiff_t>(at_));
    at_ = 0;
    // Read ahead a little past what was asked: fewer, larger reads.
    const std::size_t want = std::max(n, std::size_t{64} << 10);
    while (buffer_.size() < n && !ended_) {
      const std::size_t had = buffer_.size();
      buffer_.resize(std::max(want, had));
      const std::size_t got = source_.read(buffer_.data() + had, buffer_.size() - had);
      buffer_.resize(had + got);
      ended_ = got == 0;
    }
  }

  ByteSource& source_;
  std::span<const std::uint8_t> whole_;
  std::vector<std::uint8_t> buffer_;
  std::size_t at_ = 0;
  std::size_t offset_ = 0;
  bool ended_ = false;
};

}  // namespace voxd::encode
