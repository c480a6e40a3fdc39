#include "voxd/analysis/analysis.h"

namespace voxd {

AnalysisReport analyze_volume(const BitVolume& volume, const AnalysisOptions& options, JobControl* control) {
  AnalysisReport report;
  std::optional<BitVolume> cleaned;
  if (options.cleanup) {
    cleaned = volume.clone();
    report.cleanup = clean_up(*cleaned, *options.cleanup, options.threads);
  }
  const BitVolume& v = cleaned ? *cleaned : volume;
  auto step = [&](double progress) {
    if (!control) return;
    control->check_cancelled();
    control->set_progress(progress);
  };
  step(0.1);
  report.voxels = voxel_mass_properties(v, options.threads);
  step(0.3);
  report.components = find_components(v);
  step(0.6);
  if (options.skin) report.skin = summarize_peeling(peel_depth(v, options.threads, options.peel));
  report.peel = options.peel;
  step(0.7);
  if (options.thickness) {
    std::optional<DenseVolume<float>> computed;
    if (options.cleanup || !options.thickness_map) {
      // The thickness reports 0..1 of the last three tenths of the bar.
      const NestedSpan thickness_share(control, 0.7, 1.0);
      computed = wall_thickness(v, options.threads, control);
    }
    const DenseVolume<float>& map = computed ? *computed : *options.thickness_map;
    ThicknessAnalysis t;
    t.stats = thickness_statistics(map, options.histogram_bins);
    t.min_wall_voxels = options.min_wall_voxels;
    t.max_wall_voxels = options.max_wall_voxels;
    // Beyond the thresholds by more than the reading's noise (see
    // kWallReportTolerance).
    if (options.min_wall_voxels > 0)
      t.thin_regions = find_thickness_regions(
          map, ThicknessRegionKind::thin, static_cast<float>(options.min_wall_voxels - kWallReportTolerance),
          options.min_region_voxels);
    if (options.max_wall_voxels > 0)
      t.thick_regions = find_thickness_regions(
          map, ThicknessRegionKind::thick, static_cast<float>(options.max_wall_voxels + kWallReportTolerance),
          options.min_region_voxels);
    report.thickness = std::move(t);
  }
  step(1.0);
  return report;
}

}  // namespace voxd
