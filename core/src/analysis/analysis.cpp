#include "voxd/analysis.h"

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
  report.skin = summarize_peeling(peel_depth(v, options.threads));
  step(1.0);
  return report;
}

}  // namespace voxd
