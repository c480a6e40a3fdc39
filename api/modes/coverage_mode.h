#pragma once
// "mode": "coverage" (Thon et al.'s grey levels): each voxel's share inside
// the mesh, from rays through it (voxd/voxelize/coverage.h). Options under
// "coverage"; the job's solid is the parity solid of the same crossings.
#include <optional>

#include "api/job_mode.h"
#include "voxd/voxelize/coverage.h"

namespace voxd::api {

struct CoverageParams : ModeOptions {
  CoverageOptions options;          // sampling, rays, points, seed (threads set by the runner)
  std::optional<float> threshold;   // set: the job's volume is the bits coverage >= threshold
  bool float_values = false;        // "values": "f32" (fractions 0..1) instead of "u8" (Thon's byte)
};

const JobMode& coverage_mode();

}  // namespace voxd::api
