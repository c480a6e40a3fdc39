#pragma once
// The manufacturing analysis of a voxel model in one call: optional clean-up,
// mass properties, parts and voids, skin removal. Lengths stay in voxels here
// (regions) or model units (mass properties); the JSON layer states units.
#include <optional>

#include "voxd/analysis/cleanup.h"
#include "voxd/analysis/components.h"
#include "voxd/analysis/mass_properties.h"
#include "voxd/progress.h"
#include "voxd/analysis/skin_removal.h"
#include "voxd/analysis/thickness_regions.h"
#include "voxd/analysis/local_thickness.h"  // ThicknessStatistics
#include "voxd/analysis/wall_thickness.h"

namespace voxd {

struct AnalysisOptions {
  std::optional<CleanupOptions> cleanup;  // none: analyse the volume as voxelized
  bool thickness = true;                  // wall thickness (the costliest step)
  bool skin = true;                       // skin removal layers (needs the whole grid)
  PeelMetric peel = PeelMetric::faces;    // skin removal layers
  // Thin- and thick-wall thresholds in voxels (0 = not checked), and the
  // smallest region reported (smaller ones are sampling noise).
  double min_wall_voxels = 0.0;
  double max_wall_voxels = 0.0;
  std::uint64_t min_region_voxels = 1;
  int histogram_bins = 32;
  int threads = 0;
  // The wall thickness of `volume` when the caller has it already (the
  // service keeps one per job); ignored with clean-up, which changes the
  // volume and so its thickness.
  const DenseVolume<float>* thickness_map = nullptr;
};

struct ThicknessAnalysis {
  ThicknessStatistics stats;  // in voxels
  double min_wall_voxels = 0.0, max_wall_voxels = 0.0;
  std::vector<ThicknessRegion> thin_regions, thick_regions;  // most severe first
};

struct AnalysisReport {
  std::optional<CleanupReport> cleanup;
  MassProperties voxels;
  ComponentReport components;
  std::optional<PeelSummary> skin;  // when asked for
  PeelMetric peel = PeelMetric::faces;
  std::optional<ThicknessAnalysis> thickness;
};

// `volume` is not modified; clean-up works on a copy.
AnalysisReport analyze_volume(const BitVolume& volume, const AnalysisOptions& options, JobControl* control = nullptr);

}  // namespace voxd
