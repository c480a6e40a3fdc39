#pragma once
// Cross-sections: one plane of voxels across an axis, as an 8-bit image, so a
// client can look inside a part (walls, cavities) at a chosen height.
#include <cstdint>
#include <utility>
#include <vector>

#include "voxd/bit_volume.h"
#include "voxd/run_slab.h"

namespace voxd {

// 8-bit greyscale image, row-major (pixel (c, r) at r * width + c).
struct GreyImage8 {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> pixels;
};

// The plane of voxels with index `index` along `axis` (0 = x, 1 = y, 2 = z):
// 255 where filled, 0 where empty. Columns and rows are the remaining axes in
// x, y, z order, as for radiography(): axis 0 -> (j, k), 1 -> (i, k), 2 -> (i, j).
// Throws Error(invalid_argument) for a bad axis or an index outside
// [0, dims[axis]).
GreyImage8 cross_section(const BitVolume& volume, int axis, std::int64_t index);

// cross_section of a volume that arrives slab by slab (a stored result
// replayed from its RLE): add() the slabs, then take(). Memory is the image.
class SectionGatherer {
 public:
  // Throws like cross_section for a bad axis or index.
  SectionGatherer(const Grid& grid, int axis, std::int64_t index);
  // Layers [k0, k0 + slab.grid().dims.z) of the grid; a slab the plane
  // does not cross adds nothing.
  void add(std::int64_t k0, const BitVolume& slab);
  // The same from the slab's runs (a stored RLE read as runs): the runs of
  // the rows the plane cuts, never the grid's bits.
  void add(std::int64_t k0, const RunSlab& slab);
  GreyImage8 take() { return std::move(image_); }

 private:
  int axis_;
  std::int64_t index_;
  GreyImage8 image_;
};

// Index along `axis` of the voxel layer containing model coordinate
// `coordinate`: floor((coordinate - origin[axis]) / voxel_size). Throws
// Error(invalid_argument) when the coordinate is not finite or lies outside
// the grid, [origin, origin + dims * voxel_size).
std::int64_t section_index(const Grid& grid, int axis, double coordinate);

}  // namespace voxd
