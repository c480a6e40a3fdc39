#include "voxd/analysis/section.h"

#include <algorithm>
#include <cmath>
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

GreyImage8 cross_section(const BitVolume& volume, int axis, std::int64_t index) {
  check_axis(axis);
  const glm::i64vec3 d = volume.grid().dims;
  if (index < 0 || index >= d[axis]) {
    throw Error(ErrorCode::invalid_argument, std::string("section index along ") + axis_name(axis) + " is " +
                                                 std::to_string(index) + ", outside 0.." + std::to_string(d[axis] - 1));
  }
  const ImageSize size = projected_size(volume.grid(), axis);
  GreyImage8 image;
  image.width = size.width;
  image.height = size.height;
  image.pixels.assign(static_cast<std::size_t>(size.width) * static_cast<std::size_t>(size.height), 0);
  std::uint8_t* out = image.pixels.data();
  if (axis == 2) {  // rows are the volume's x-rows of slab `index`
    for (std::int64_t j = 0; j < d.y; ++j) row_to_bytes(volume.row(j, index), d.x, out + j * d.x);
  } else if (axis == 1) {  // row k of the image is x-row (index, k)
    for (std::int64_t k = 0; k < d.z; ++k) row_to_bytes(volume.row(index, k), d.x, out + k * d.x);
  } else {  // one bit per x-row: column j, row k
    const std::int64_t word = index >> 6;
    const int bit = static_cast<int>(index & 63);
    for (std::int64_t k = 0; k < d.z; ++k) {
      for (std::int64_t j = 0; j < d.y; ++j) out[k * d.y + j] = ((volume.row(j, k)[word] >> bit) & 1u) ? 255 : 0;
    }
  }
  return image;
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
