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
  // Regions reading under min_wall (over max_wall) by more than the
  // lattice's noise (kWallReportTolerance), most severe first. Those beyond
  // by less than the error bound too are marginal (certainly_beyond).
  std::vector<ThicknessRegion> thin_regions, thick_regions;
  // Regions reading within the error bound on the good side of the
  // thresholds: min_wall - tolerance up to a voxel more (a voxel less for
  // max_wall), that no thin (thick) region is part of. The wall may be on
  // either side.
  std::vector<ThicknessRegion> near_min_wall, near_max_wall;
};

// Whether a thin (thick) region of `t` reads beyond its threshold by more
// than the error bound (wall_thickness_error_bound()) and the tolerance, so
// that the wall itself is beyond it; otherwise it is marginal.
bool certainly_beyond(const ThicknessAnalysis& t, const ThicknessRegion& region, ThicknessRegionKind kind);

// The verdict the thickness analysis can sign: fail when some region is
// certainly beyond a threshold; inconclusive when some region is within
// the error bound of one (marginal) and none certainly beyond; pass when
// none is either; none without thresholds.
enum class ThicknessVerdict { none, pass, fail, inconclusive };
ThicknessVerdict thickness_verdict(const ThicknessAnalysis& t);

// For an inconclusive verdict: the largest voxel (in voxels of this grid)
// at which every marginal region's reading, where it is now, would lie
// beyond the error bound of its threshold, so that a finer grid decides it.
// Never under a twentieth of the threshold (a wall that reads exactly
// min_wall is decided by no grid). Nullopt unless inconclusive.
std::optional<double> deciding_voxel_size(const ThicknessAnalysis& t);

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
