#pragma once
// How far a thickness measure's reading can be from the wall it measures,
// in voxels: local thickness (voxd/analysis/local_thickness.h) and wall
// thickness (voxd/analysis/wall_thickness.h) each state theirs, and their
// reports say it in voxels and model units the same way.
#include <string>

namespace voxd {

struct ThicknessErrorBound {
  double below_voxels = 0.0;  // reported >= true - below_voxels
  double above_voxels = 0.0;  // reported <= true + above_voxels
};

// "-B to +A voxels (-b to +a model units)" for voxels of `voxel_size`.
std::string voxels_and_model_units(const ThicknessErrorBound& bound, double voxel_size);

}  // namespace voxd
