#include "voxd/analysis/section.h"

#include <algorithm>
#include <cmath>
#include <span>
#include <string>

#include "voxd/error.h"
#include "voxd/analysis/radiography.h"

namespace voxd {
namespace {

const char* axis_name(int axis) { return axis == 0 ? "x" : axis == 1 ? "y" : "z"; }

void check_axis(int axis) {
  if (axis < 0 || axis > 2) {
    throw Error(ErrorCode::invalid_argument, "axis must be 0 (x), 1 (y) or 2 (z), got " + std::to_string(axis));
  }
}

// Expands the bits of one row (x) into bytes 255/0.
void row_to_bytes(const std::uint64_t* row, std::int64_t n, std::uint8_t* out) {
  for (std::int64_t w = 0; w * 64 < n; ++w) {
    const std::uint64_t x = row[w];
    const std::int64_t end = std::min<std::int64_t>(64, n - w * 64);
    for (std::int64_t b = 0; b < end; ++b) out[w * 64 + b] = ((x >> b) & 1u) ? 255 : 0;
  }
}

}  // namespace

SectionGatherer::SectionGatherer(const Grid& grid, int axis, std::int64_t index) : axis_(axis), index_(index) {
  check_axis(axis);
  if (index < 0 || index >= grid.dims[axis]) {
    throw Error(ErrorCode::invalid_argument, std::string("section index along ") + axis_name(axis) + " is " +
                                                 std::to_string(index) + ", outside 0.." + std::to_string(grid.dims[axis] - 1));
  }
  const ImageSize size = projected_size(grid, axis);
  image_.width = size.width;
  image_.height = size.height;
  image_.pixels.assign(static_cast<std::size_t>(size.width) * static_cast<std::size_t>(size.height), 0);
}

void SectionGatherer::add(std::int64_t k0, const BitVolume& slab) {
  const glm::i64vec3 d = slab.grid().dims;
  std::uint8_t* out = image_.pixels.data();
  if (axis_ == 2) {  // rows are the volume's x-rows of layer `index`
    if (index_ < k0 || index_ >= k0 + d.z) return;
    for (std::int64_t j = 0; j < d.y; ++j) row_to_bytes(slab.row(j, index_ - k0), d.x, out + j * d.x);
  } else if (axis_ == 1) {  // row k of the image is x-row (index, k)
    for (std::int64_t k = 0; k < d.z; ++k) row_to_bytes(slab.row(index_, k), d.x, out + (k0 + k) * d.x);
  } else {  // one bit per x-row: column j, row k
    const std::int64_t word = index_ >> 6;
    const int bit = static_cast<int>(index_ & 63);
    for (std::int64_t k = 0; k < d.z; ++k) {
      for (std::int64_t j = 0; j < d.y; ++j) out[(k0 + k) * d.y + j] = ((slab.row(j, k)[word] >> bit) & 1u) ? 255 : 0;
    }
  }
}

void SectionGatherer::add(std::int64_t k0, const RunSlab& slab) {
  const glm::i64vec3 d = slab.grid().dims;
  std::uint8_t* out = image_.pixels.data();
  const auto paint = [](std::span<const std::uint32_t> runs, std::uint8_t* row) {
    for (std::size_t r = 0; r < runs.size(); r += 2) std::fill(row + runs[r], row + runs[r + 1], std::uint8_t{255});
  };
  if (axis_ == 2) {
    if (index_ < k0 || index_ >= k0 + d.z) return;
    for (std::int64_t j = 0; j < d.y; ++j) paint(slab.row(j, index_ - k0), out + j * d.x);
  } else if (axis_ == 1) {
    for (std::int64_t k = 0; k < d.z; ++k) paint(slab.row(index_, k), out + (k0 + k) * d.x);
  } else {  // whether each x-row's runs hold voxel `index`: an odd count of bounds up to it
    const auto at = static_cast<std::uint32_t>(index_);
    for (std::int64_t k = 0; k < d.z; ++k)
      for (std::int64_t j = 0; j < d.y; ++j) {
        const std::span<const std::uint32_t> runs = slab.row(j, k);
        const auto bounds = std::upper_bound(runs.begin(), runs.end(), at) - runs.begin();
        out[(k0 + k) * d.y + j] = bounds % 2 == 1 ? 255 : 0;
      }
  }
}

GreyImage8 cross_section(const BitVolume& volume, int axis, std::int64_t index) {
  SectionGatherer section(volume.grid(), axis, index);
  section.add(0, volume);
  return section.take();
}

std::int64_t section_index(const Grid& grid, int axis, double coordinate) {
  check_axis(axis);
  const double lo = grid.origin[axis];
  const double hi = lo + static_cast<double>(grid.dims[axis]) * grid.voxel_size;
  if (!std::isfinite(coordinate) || coordinate < lo || coordinate >= hi) {
    throw Error(ErrorCode::invalid_argument, std::string("section ") + axis_name(axis) + " = " + std::to_string(coordinate) +
                                                 " is outside the grid, which spans [" + std::to_string(lo) + ", " +
                                                 std::to_string(hi) + ")");
  }
  const double t = std::floor((coordinate - lo) / grid.voxel_size);
  // Rounding can push a coordinate just below hi onto dims[axis]; it belongs to the last layer.
  return std::clamp<std::int64_t>(static_cast<std::int64_t>(t), 0, grid.dims[axis] - 1);
}

}  // namespace voxd
