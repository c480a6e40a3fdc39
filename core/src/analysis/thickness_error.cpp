#include "voxd/analysis/thickness_error.h"

#include <cstdio>

namespace voxd {

std::string voxels_and_model_units(const ThicknessErrorBound& bound, double voxel_size) {
  char text[160];
  std::snprintf(text, sizeof text, "-%g to +%g voxels (-%g to +%g model units)", bound.below_voxels,
                bound.above_voxels, bound.below_voxels * voxel_size, bound.above_voxels * voxel_size);
  return text;
}

}  // namespace voxd
