#pragma once
// Bytes read front to back, a piece at a time: a stored result read where it
// lies (a mapped file) or fetched as it is read (chunks from a shared store),
// so that replaying it never needs all of it in memory or on disk.
#include <cstddef>
#include <cstdint>
#include <span>

namespace voxd {

class ByteSource {
 public:
  virtual ~ByteSource() = default;
  // Up to `size` next bytes into `out`; 0 only at the end. Throws
  // voxd::Error when the bytes cannot be had (a store that lost them).
  virtual std::size_t read(std::uint8_t* out, std::size_t size) = 0;
  // All of the bytes at once, when they are in memory already (a span or a
  // mapped file): readers then take views instead of copies. Empty when not.
  virtual std::span<const std::uint8_t> whole() const { return {}; }
};

// A span in memory as a source.
class SpanSource final : public ByteSource {
 public:
  explicit SpanSource(std::span<const std::uint8_t> data) : data_(data) {}
  std::size_t read(std::uint8_t* out, std::size_t size) override;
  std::span<const std::uint8_t> whole() const override { return data_; }

 private:
  std::span<const std::uint8_t> data_;
  std::size_t at_ = 0;
};

}  // namespace voxd
