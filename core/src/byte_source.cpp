#include "voxd/byte_source.h"

#include <algorithm>
#include <cstring>

namespace voxd {

std::size_t SpanSource::read(std::uint8_t* out, std::size_t size) {
  const std::size_t n = std::min(size, data_.size() - at_);
  if (n > 0) std::memcpy(out, data_.data() + at_, n);
  at_ += n;
  return n;
}

}  // namespace voxd
