#include "voxd/bit_volume.h"

#include <bit>
#include <string>

#include "voxd/error.h"
#include "voxd/parallel.h"

namespace voxd {

BitVolume::BitVolume(const Grid& grid) : grid_(grid), row_words_((grid.dims.x + 63) / 64) {
  if (grid.dims.x <= 0 || grid.dims.y <= 0 || grid.dims.z <= 0)
    throw Error(ErrorCode::invalid_argument, "grid dims must be positive");
  const std::size_t n = word_count();
  words_.reset(static_cast<std::uint64_t*>(std::calloc(n, sizeof(std::uint64_t))));
  if (!words_)
    throw Error(ErrorCode::limit_exceeded,
                "cannot allocate " + std::to_string(n * 8 / (1 << 20)) + " MiB for the voxel volume");
}

std::uint64_t BitVolume::count() const {
  std::uint64_t total = 0;
  const std::size_t n = word_count();
  const std::uint64_t* w = data();
  for (std::size_t i = 0; i < n; ++i) total += static_cast<std::uint64_t>(std::popcount(w[i]));
  return total;
}

void BitVolume::merge_or(const BitVolume& other) {
  if (other.grid_.dims != grid_.dims) throw Error(ErrorCode::invalid_argument, "merge_or: grids differ");
  const std::size_t slab = slab_words();
  parallel_for(0, grid_.dims.z, 16, 0, [&](std::int64_t k0, std::int64_t k1) {
    std::uint64_t* dst = this->slab(k0);
    const std::uint64_t* src = other.slab(k0);
    for (std::size_t i = 0, n = slab * static_cast<std::size_t>(k1 - k0); i < n; ++i) dst[i] |= src[i];
  });
}

}  // namespace voxd
