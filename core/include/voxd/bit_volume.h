#pragma once
// Bit-packed binary volume: one bit per voxel, x fastest, then y, then z.
// Each x-row starts on a 64-bit word (row_words() words per row), so a row is
// contiguous and a z-slab is contiguous: the layout every voxelizer fills and
// every encoder reads slab by slab. Bits past dims.x in a row are always zero.
// Memory: dims.y * dims.z * ceil(dims.x / 64) * 8 bytes (N^3/8 for N % 64 == 0).
#include <cstdint>
#include <memory>
#include <span>

#include "voxd/grid.h"

namespace voxd {

// Memory of a BitVolume with these dims (rows padded to 64-bit words), e.g.
// to decide before allocating. dims are at most kMaxGridDim each, so this
// cannot overflow.
inline std::uint64_t bit_volume_bytes(const glm::i64vec3& dims) {
  return static_cast<std::uint64_t>((dims.x + 63) / 64) * 8 * static_cast<std::uint64_t>(dims.y) *
         static_cast<std::uint64_t>(dims.z);
}

class BitVolume {
 public:
  BitVolume() = default;
  // Zero-filled. Memory comes straight from the OS (lazily zeroed pages, huge
  // pages where allowed) so untouched memory costs nothing until the parallel
  // voxelizer writes it. Throws Error(limit_exceeded) if the allocation fails.
  explicit BitVolume(const Grid& grid);

  const Grid& grid() const { return grid_; }
  std::int64_t row_words() const { return row_words_; }
  std::size_t slab_words() const { return static_cast<std::size_t>(row_words_ * grid_.dims.y); }
  std::size_t word_count() const { return slab_words() * static_cast<std::size_t>(grid_.dims.z); }
  std::size_t byte_size() const { return word_count() * sizeof(std::uint64_t); }

  std::uint64_t* data() { return words_.get(); }
  const std::uint64_t* data() const { return words_.get(); }
  std::uint64_t* slab(std::int64_t k) { return data() + static_cast<std::size_t>(k) * slab_words(); }
  const std::uint64_t* slab(std::int64_t k) const { return data() + static_cast<std::size_t>(k) * slab_words(); }
  std::uint64_t* row(std::int64_t j, std::int64_t k) { return slab(k) + j * row_words_; }
  const std::uint64_t* row(std::int64_t j, std::int64_t k) const { return slab(k) + j * row_words_; }

  bool get(std::int64_t i, std::int64_t j, std::int64_t k) const {
    return (row(j, k)[i >> 6] >> (i & 63)) & 1u;
  }
  void set(std::int64_t i, std::int64_t j, std::int64_t k, bool value) {
    std::uint64_t& w = row(j, k)[i >> 6];
    const std::uint64_t bit = std::uint64_t{1} << (i & 63);
    w = value ? (w | bit) : (w & ~bit);
  }

  // Number of set voxels.
  std::uint64_t count() const;
  // Voxel-wise OR / AND with a volume of the same grid.
  void merge_or(const BitVolume& other);
  // A deep copy (volumes are move-only so a copy is always deliberate).
  BitVolume clone() const;

 private:
  struct Unmap {
    std::size_t bytes;  // no initializer: keeps Unmap default-constructible inside BitVolume
    void operator()(std::uint64_t* p) const;
  };
  Grid grid_;
  std::int64_t row_words_ = 0;
  std::unique_ptr<std::uint64_t[], Unmap> words_;
};

}  // namespace voxd
