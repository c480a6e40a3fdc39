#include "voxd/analysis/analysis.h"

#include <algorithm>
#include <cmath>
#include <limits>

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
  if (options.skin) report.skin = summarize_peeling(peel_depth(v, options.threads, options.peel), options.threads);
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
    t.stats = thickness_statistics(map, options.histogram_bins, options.threads);
    t.min_wall_voxels = options.min_wall_voxels;
    t.max_wall_voxels = options.max_wall_voxels;
    // Beyond the thresholds by more than the reading's noise (see
    // kWallReportTolerance); and within the error bound on the good side:
    // found with the threshold moved a bound further, less those holding a
    // region beyond it (listed above). All from one pass over the map.
    const ThicknessErrorBound bound = wall_thickness_error_bound();
    const double thin_at = options.min_wall_voxels - kWallReportTolerance;
    const double thick_at = options.max_wall_voxels + kWallReportTolerance;
    std::vector<ThicknessRegionQuery> queries;
    if (options.min_wall_voxels > 0) {
      queries.push_back({ThicknessRegionKind::thin, static_cast<float>(thin_at)});
      queries.push_back({ThicknessRegionKind::thin, static_cast<float>(thin_at + bound.below_voxels)});
    }
    if (options.max_wall_voxels > 0) {
      queries.push_back({ThicknessRegionKind::thick, static_cast<float>(thick_at)});
      queries.push_back({ThicknessRegionKind::thick, static_cast<float>(thick_at - bound.above_voxels)});
    }
    std::vector<std::vector<ThicknessRegion>> found =
        find_thickness_regions(map, queries, options.min_region_voxels, options.threads);
    std::size_t next = 0;
    if (options.min_wall_voxels > 0) {
      t.thin_regions = std::move(found[next++]);
      for (ThicknessRegion& r : found[next++])
        if (r.extreme_thickness >= static_cast<float>(thin_at)) t.near_min_wall.push_back(r);
    }
    if (options.max_wall_voxels > 0) {
      t.thick_regions = std::move(found[next++]);
      for (ThicknessRegion& r : found[next++])
        if (r.extreme_thickness <= static_cast<float>(thick_at)) t.near_max_wall.push_back(r);
    }
    report.thickness = std::move(t);
  }
  step(1.0);
  return report;
}

bool certainly_beyond(const ThicknessAnalysis& t, const ThicknessRegion& region, ThicknessRegionKind kind) {
  const ThicknessErrorBound bound = wall_thickness_error_bound();
  // A reading r of a wall w has w - below <= r <= w + above: the wall is
  // under min_wall when r + below < min_wall, past the tolerance.
  if (kind == ThicknessRegionKind::thin)
    return region.extreme_thickness < t.min_wall_voxels - kWallReportTolerance - bound.above_voxels;
  return region.extreme_thickness > t.max_wall_voxels + kWallReportTolerance + bound.below_voxels;
}

ThicknessVerdict thickness_verdict(const ThicknessAnalysis& t) {
  if (t.min_wall_voxels <= 0 && t.max_wall_voxels <= 0) return ThicknessVerdict::none;
  for (const ThicknessRegion& r : t.thin_regions)
    if (certainly_beyond(t, r, ThicknessRegionKind::thin)) return ThicknessVerdict::fail;
  for (const ThicknessRegion& r : t.thick_regions)
    if (certainly_beyond(t, r, ThicknessRegionKind::thick)) return ThicknessVerdict::fail;
  const bool marginal =
      !t.thin_regions.empty() || !t.thick_regions.empty() || !t.near_min_wall.empty() || !t.near_max_wall.empty();
  return marginal ? ThicknessVerdict::inconclusive : ThicknessVerdict::pass;
}

std::optional<double> deciding_voxel_size(const ThicknessAnalysis& t) {
  if (thickness_verdict(t) != ThicknessVerdict::inconclusive) return std::nullopt;
  const ThicknessErrorBound bound = wall_thickness_error_bound();
  // Decided at voxel h' (in these voxels) when the reading is beyond the
  // threshold by more than (bound + tolerance) h'.
  const double margin = std::max(bound.below_voxels, bound.above_voxels) + kWallReportTolerance;
  double voxel = std::numeric_limits<double>::infinity(), floor = voxel;
  auto take = [&](const std::vector<ThicknessRegion>& regions, double threshold) {
    if (threshold <= 0) return;
    floor = std::min(floor, threshold / 20.0);
    for (const ThicknessRegion& r : regions)
      voxel = std::min(voxel, std::abs(static_cast<double>(r.extreme_thickness) - threshold) / margin);
  };
  take(t.thin_regions, t.min_wall_voxels);
  take(t.near_min_wall, t.min_wall_voxels);
  take(t.thick_regions, t.max_wall_voxels);
  take(t.near_max_wall, t.max_wall_voxels);
  return std::min(1.0, std::max(voxel, floor));
}

}  // namespace voxd
