#include "voxd/bit_volume.h"

#include <atomic>
#include <algorithm>
#include <bit>
#include <cstdlib>
#include <string>

#include "voxd/error.h"
#include "voxd/parallel.h"
#include "voxd/volume_memory.h"

namespace voxd {

BitVolume::BitVolume(const Grid& grid) : grid_(grid), row_words_((grid.dims.x + 63) / 64) {
  if (grid.dims.x <= 0 || grid.dims.y <= 0 || grid.dims.z <= 0)
    throw Error(ErrorCode::invalid_argument, "grid dims must be positive");
  const std::size_t bytes = word_count() * sizeof(std::uint64_t);
  try {
    words_ = std::unique_ptr<std::uint64_t[], Unmap>(static_cast<std::uint64_t*>(allocate_volume_memory(bytes, true)),
                                                     Unmap{bytes});
  } catch (const std::bad_alloc&) {
    throw Error(ErrorCode::limit_exceeded, "cannot allocate " + std::to_string(bytes >> 20) + " MiB for the voxel volume");
  }
}

void BitVolume::Unmap::operator()(std::uint64_t* p) const { free_volume_memory(p, bytes); }

// Slabs per parallel chunk: at least 2 MiB of words, so small volumes stay on
// the calling thread instead of paying for threads.
static std::int64_t slabs_per_chunk(std::size_t slab_words) {
  return std::max<std::int64_t>(16, static_cast<std::int64_t>((std::size_t{1} << 18) / std::max<std::size_t>(slab_words, 1)));
}

std::uint64_t BitVolume::count() const {
  std::atomic<std::uint64_t> total{0};
  const std::size_t slab = slab_words();
  parallel_for(0, grid_.dims.z, slabs_per_chunk(slab), 0, [&](std::int64_t k0, std::int64_t k1) {
    const std::uint64_t* w = this->slab(k0);
    std::uint64_t sum = 0;
    for (std::size_t i = 0, n = slab * static_cast<std::size_t>(k1 - k0); i < n; ++i)
      sum += static_cast<std::uint64_t>(std::popcount(w[i]));
    total.fetch_add(sum, std::memory_order_relaxed);
  });
  return total.load();
}

void BitVolume::merge_or(const BitVolume& other) {
  if (other.grid_.dims != grid_.dims) throw Error(ErrorCode::invalid_argument, "merge_or: grids differ");
  const std::size_t slab = slab_words();
  parallel_for(0, grid_.dims.z, slabs_per_chunk(slab), 0, [&](std::int64_t k0, std::int64_t k1) {
    std::uint64_t* dst = this->slab(k0);
    const std::uint64_t* src = other.slab(k0);
    for (std::size_t i = 0, n = slab * static_cast<std::size_t>(k1 - k0); i < n; ++i) dst[i] |= src[i];
  });
}

BitVolume BitVolume::clone() const {
  BitVolume copy(grid_);
  // On every thread, as the copy's fresh pages are faulted in where they are
  // written (wall thickness copies the solid twice: 7% of its time on 16
  // threads, on one).
  const std::size_t slab = slab_words();
  parallel_for(0, grid_.dims.z, slabs_per_chunk(slab), 0, [&](std::int64_t k0, std::int64_t k1) {
    std::copy(this->slab(k0), this->slab(k0) + slab * static_cast<std::size_t>(k1 - k0), copy.slab(k0));
  });
  return copy;
}

}  // namespace voxd
