#pragma once
// The manufacturing analysis of a voxel model in one call: optional clean-up,
// mass properties, parts and voids, skin removal. Lengths stay in voxels here
// (regions) or model units (mass properties); the JSON layer states units.
#include <optional>

#include "voxd/cleanup.h"
#include "voxd/components.h"
#include "voxd/mass_properties.h"
#include "voxd/progress.h"
#include "voxd/skin_removal.h"

namespace voxd {

struct AnalysisOptions {
  std::optional<CleanupOptions> cleanup;  // none: analyse the volume as voxelized
  int threads = 0;
};

struct AnalysisReport {
  std::optional<CleanupReport> cleanup;
  MassProperties voxels;
  ComponentReport components;
  PeelSummary skin;
};

// `volume` is not modified; clean-up works on a copy.
AnalysisReport analyze_volume(const BitVolume& volume, const AnalysisOptions& options, JobControl* control = nullptr);

}  // namespace voxd
