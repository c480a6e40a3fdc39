// The analysis report (kind "analysis"): mass properties, parts and voids,
// wall thickness, skin removal; over a streamed job's slabs without the
// measures that need the whole grid.
#include "server/jobs/analyses/analysis_support.h"

#include "api/analysis_json.h"
#include "voxd/analysis/analysis.h"
#include "voxd/analysis/components.h"
#include "voxd/analysis/mass_properties.h"
#include "voxd/encode/rle_slabs.h"

namespace voxd::server {
namespace {

// The report with what it should be read with: the job's inside test and
// warnings (an open or inside-out mesh, an implausible size).
std::string report_json(const AnalysisReport& report, const JobSnapshot& job) {
  nlohmann::json doc = api::analysis_to_json(report, job.grid, job.mesh, job.mesh_mass);
  if (job.inside) doc["inside"] = api::to_json(*job.inside);
  doc["warnings"] = api::to_json(job.warnings);
  return doc.dump();
}


class ReportAnalysis final : public JobAnalysisKind {
 public:
  api::AnalysisKind kind() const override { return api::AnalysisKind::analysis; }

  std::string compute(const AnalysisInput& in, const BitVolume& volume) const override {
    const api::AnalysisRequest& r = in.request;
    const JobSnapshot& job = in.job;
    AnalysisOptions options;
    if (r.cleanup != "none") options.cleanup = CleanupOptions{true, true, r.cleanup == "sheets"};
    options.thickness = r.thickness;
    options.skin = r.skin;
    options.peel = r.peel_metric;
    options.min_wall_voxels = r.min_wall.value_or(0) / job.grid.voxel_size;
    options.max_wall_voxels = r.max_wall.value_or(0) / job.grid.voxel_size;
    // Kept while the rest of the report is computed.
    JobThicknessMap map;
    const bool map_first = r.thickness && !options.cleanup;
    if (map_first) {
      // The thickness map takes most of the time: most of the bar.
      const NestedSpan map_share(in.control, 0.0, 0.8);
      map = job_thickness_map(volume, in.artifacts, in.control);
      options.thickness_map = map.map.get();
    }
    const NestedSpan report_share(in.control, map_first ? 0.8 : 0.0, 1.0);
    const AnalysisReport report = analyze_volume(volume, options, in.control);
    return report_json(report, job);
  }

  bool streams_over_slabs(const api::AnalysisRequest& r) const override {
    return r.cleanup == "none" && !r.thickness && !r.skin;
  }

  // Mass properties, parts and voids from the slabs: the bytes compute()
  // makes for the same request.
  std::string over_slabs(const AnalysisInput& in) const override {
    const JobSnapshot& job = in.job;
    VoxelMassAccumulator mass(job.grid);
    ComponentLabeller components(job.grid);
    replay_runs(in, [&](std::int64_t k0, const RunSlab& slab) {
      mass.add(k0, slab);
      components.add(k0, slab);
    });
    AnalysisReport report;
    report.voxels = mass.result();
    report.components = components.finish();
    report.peel = in.request.peel_metric;
    return report_json(report, job);
  }

  // A slab of runs. The labeller's two layers of runs a phase are a
  // layer's runs: a few per row of a real part.
  std::uint64_t over_slabs_memory(const api::AnalysisRequest&, const Grid& grid) const override {
    return run_slab_bytes(grid);
  }

  // The distance transform and the thickness map (floats), the labels of
  // parts and voids or the peel depths (32 bits a voxel), bit copies.
  std::uint64_t whole_grid_bytes_per_voxel(const api::AnalysisRequest& r) const override { return r.thickness ? 18 : 6; }

  std::string needs_whole_grid(const api::AnalysisRequest& r) const override {
    return std::string(r.thickness ? "wall thickness" : r.skin ? "skin removal" : "clean-up") + " (in the analysis)";
  }
};

}  // namespace

const JobAnalysisKind& report_analysis() {
  static const ReportAnalysis kind;
  return kind;
}

}  // namespace voxd::server
