#pragma once
// Dense volume of one value per voxel (grey levels, distances, palette
// indices, colours), x fastest, then y, then z, no row padding. Large
// volumes live on huge pages (voxd/volume_memory.h).
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <type_traits>
#include <vector>

#include "voxd/grid.h"
#include "voxd/volume_memory.h"

namespace voxd {

struct Rgba8 {
  std::uint8_t r = 0, g = 0, b = 0, a = 0;
  friend bool operator==(const Rgba8&, const Rgba8&) = default;
};

template <typename T>
class DenseVolume {
 public:
  DenseVolume() = default;
  // Filled with `fill`; a fill of zero bytes (the default) asks for zeroed
  // memory instead of writing it (VolumeInit::zeroed): fresh pages are zero.
  explicit DenseVolume(const Grid& grid, T fill = T{})
      : grid_(grid), values_(VolumeAllocator<T>(all_zero(fill) ? VolumeInit::zeroed : VolumeInit::values)) {
    if (values_.get_allocator().init == VolumeInit::zeroed)
      values_.resize(grid.voxel_count());
    else
      values_.assign(grid.voxel_count(), fill);
  }
  // Values left as the memory held them, for a volume about to be
  // overwritten whole (read from a file): nothing is written or cleared.
  struct Uninitialized {};
  DenseVolume(const Grid& grid, Uninitialized) : grid_(grid), values_(VolumeAllocator<T>(VolumeInit::none)) {
    values_.resize(grid.voxel_count());
  }

  const Grid& grid() const { return grid_; }
  // The same values placed on another grid of the same dims (a reused slab
  // moved up the grid). Throws std::invalid_argument for other dims.
  void move_to(const Grid& grid) {
    if (grid.dims != grid_.dims) throw std::invalid_argument("DenseVolume::move_to: a grid of other dims");
    grid_ = grid;
  }
  std::size_t index(std::int64_t i, std::int64_t j, std::int64_t k) const {
    return static_cast<std::size_t>(i + grid_.dims.x * (j + grid_.dims.y * k));
  }
  T& at(std::int64_t i, std::int64_t j, std::int64_t k) { return values_[index(i, j, k)]; }
  const T& at(std::int64_t i, std::int64_t j, std::int64_t k) const { return values_[index(i, j, k)]; }
  std::size_t slab_size() const { return static_cast<std::size_t>(grid_.dims.x * grid_.dims.y); }
  const T* slab(std::int64_t k) const { return values_.data() + static_cast<std::size_t>(k) * slab_size(); }
  T* slab(std::int64_t k) { return values_.data() + static_cast<std::size_t>(k) * slab_size(); }
  VolumeVector<T>& values() { return values_; }
  const VolumeVector<T>& values() const { return values_; }

 private:
  static bool all_zero(const T& value) {
    if constexpr (!std::is_trivially_copyable_v<T>) {
      return false;
    } else {
      unsigned char bytes[sizeof(T)];
      std::memcpy(bytes, &value, sizeof(T));
      for (unsigned char b : bytes)
        if (b != 0) return false;
      return true;
    }
  }

  Grid grid_;
  VolumeVector<T> values_;
};

}  // namespace voxd
