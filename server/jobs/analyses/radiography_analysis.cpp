// Radiography: the thickness of the solid along each ray of an axis.
#include "server/jobs/analyses/analysis_support.h"

#include "server/jobs/job_store.h"

namespace voxd::server {
namespace {

// The picture, then the maps freed on every thread: a gigabyte at 8192^3,
// which one thread would unmap before the answer goes out.
std::string result_freeing(const AnalysisInput& in, ThicknessImage maps) {
  std::string result = radiography_result(in, maps);
  free_on_every_thread(maps);
  return result;
}

class RadiographyAnalysis final : public JobAnalysisKind {
 public:
  api::AnalysisKind kind() const override { return api::AnalysisKind::radiography; }

  std::string compute(const AnalysisInput& in, const BitVolume& volume) const override {
    const std::optional<BitVolume> peeled_model = peeled_volume(in.request, volume);
    return result_freeing(in, radiography(peeled_model ? *peeled_model : volume, in.request.axis));
  }

  bool streams_over_slabs(const api::AnalysisRequest& r) const override { return r.peel == 0; }

  // Over the stored runs: the cost is the runs and where rays' runs begin
  // and end, not the grid's bits.
  std::string over_slabs(const AnalysisInput& in) const override {
    RadiographyAccumulator image(in.job.grid, in.request.axis);
    replay_runs(in, [&](std::int64_t k0, const RunSlab& slab) { image.add(k0, slab); });
    return result_freeing(in, image.take());
  }

  // Its four maps of 32 bits a pixel and the PNG; a slab of runs and the
  // seam's copy of its last layer.
  std::uint64_t over_slabs_memory(const api::AnalysisRequest& r, const Grid& grid) const override {
    return (4 * 4 + 2 + 4) * image_pixels(grid, r.axis) + 2 * run_slab_bytes(grid);
  }

  std::uint64_t whole_grid_bytes_per_voxel(const api::AnalysisRequest&) const override { return 6; }

  std::string needs_whole_grid(const api::AnalysisRequest&) const override {
    return "a radiography of the peeled model (peel)";
  }
};

}  // namespace

const JobAnalysisKind& radiography_analysis() {
  static const RadiographyAnalysis kind;
  return kind;
}

}  // namespace voxd::server
