#pragma once
// Growable output buffer for one encoded slab. Unlike std::vector it does not
// zero-fill when growing, and appends check capacity once per value, which
// keeps the per-run cost of the encoders to a few instructions.
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <memory>
#include <span>

#include "encode/varint.h"

namespace voxd::encode {

class ByteBuffer {
 public:
  // Empties the buffer, keeping `front_room` bytes at the start that the
  // caller may fill later (e.g. a block header whose length is not yet known).
  void reset(std::size_t front_room = 0) {
    size_ = 0;
    make_room(front_room);
    size_ = front_room;
  }
  void put_byte(std::uint8_t b) {
    make_room(1);
    data_[size_++] = b;
  }
  void put_varint(std::uint64_t v) {
    make_room(kMaxVarintBytes);
    size_ = static_cast<std::size_t>(encode::put_varint(data_.get() + size_, v) - data_.get());
  }
  void put_bytes(const void* p, std::size_t n) {
    make_room(n);
    std::memcpy(data_.get() + size_, p, n);
    size_ += n;
  }
  // Appends `count` copies of the two bytes (a, b).
  void put_pairs(std::uint8_t a, std::uint8_t b, std::size_t count) {
    make_room(2 * count);
    std::uint8_t* p = data_.get() + size_;
    for (std::size_t i = 0; i < count; ++i) {
      p[2 * i] = a;
      p[2 * i + 1] = b;
    }
    size_ += 2 * count;
  }

  std::uint8_t* data() { return data_.get(); }
  const std::uint8_t* data() const { return data_.get(); }
  std::size_t size() const { return size_; }
  std::span<const std::uint8_t> bytes() const { return {data_.get(), size_}; }

 private:
  void make_room(std::size_t n) {
    if (capacity_ - size_ >= n) return;
    const std::size_t wanted = std::max<std::size_t>({size_ + n, 2 * capacity_, 4096});
    auto bigger = std::make_unique_for_overwrite<std::uint8_t[]>(wanted);
    if (size_ > 0) std::memcpy(bigger.get(), data_.get(), size_);
    data_ = std::move(bigger);
    capacity_ = wanted;
  }

  std::unique_ptr<std::uint8_t[]> data_;
  std::size_t size_ = 0;
  std::size_t capacity_ = 0;
};

}  // namespace voxd::encode
