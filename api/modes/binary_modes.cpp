// "mode": "solid", "surface" and "solid+surface": the job's result is bits,
// the voxelization of voxd/voxelize/voxelize.h with the job's inside test.
// No options object; the three differ only in which voxels they fill.
#include "api/job_mode.h"
#include "api/job_params.h"
#include "voxd/voxelize/runs.h"
#include "voxd/voxelize/streamed.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd::api {
namespace {

class BinaryMode final : public JobMode {
 public:
  BinaryMode(std::string_view name, VoxelMode mode, std::string_view summary) : name_(name), summary_(summary), mode_(mode) {}
  std::string_view name() const override { return name_; }
  std::string_view summary() const override { return summary_; }
  VoxelMode voxel_mode() const override { return mode_; }
  std::string_view stage_name() const override { return "voxelize"; }

  JobVolumes run(const ModeInput& in) const override {
    VoxelizeOptions options;
    options.mode = mode_;
    options.inside = in.params.inside;
    options.threads = in.threads;
    JobVolumes r;
    r.solid = std::make_shared<const BitVolume>(voxelize(in.mesh, in.grid, options, in.control));
    return r;
  }

  std::optional<std::string> streaming_refusal(const JobParams& params) const override {
    VoxelizeOptions options;
    options.mode = mode_;
    options.inside = params.inside;
    if (can_stream(options)) return std::nullopt;
    return "the " + std::string(to_string(params.inside)) +
           " inside test needs the whole grid; only \"inside\": \"parity\" streams slab by slab";
  }

  nlohmann::json run_streamed(const ModeInput& in, std::int64_t slab_layers, const BitSlabConsumer& bits,
                              const ValueSlabConsumer&) const override {
    VoxelizeOptions options;
    options.mode = mode_;
    options.inside = in.params.inside;
    options.threads = in.threads;
    voxelize_streamed(in.mesh, in.grid, options, slab_layers, bits, in.control);
    return nullptr;
  }

  bool makes_runs(const JobParams& params) const override {
    VoxelizeOptions options;
    options.mode = mode_;
    options.inside = params.inside;
    return can_make_runs(options);
  }

  void run_runs(const ModeInput& in, const RunSlabConsumer& runs) const override {
    VoxelizeOptions options;
    options.mode = mode_;
    options.inside = in.params.inside;
    options.threads = in.threads;
    voxelize_runs(in.mesh, in.grid, options, runs, in.control, in.layers, in.prepare_runs);
  }

 private:
  std::string_view name_, summary_;
  VoxelMode mode_;
};

}  // namespace

const JobMode& solid_mode() {
  static const BinaryMode mode(to_string(VoxelMode::solid), VoxelMode::solid, "bits: the voxels whose centres are inside");
  return mode;
}
const JobMode& surface_mode() {
  static const BinaryMode mode(to_string(VoxelMode::surface), VoxelMode::surface, "bits: the voxels the surface passes through");
  return mode;
}
const JobMode& solid_and_surface_mode() {
  static const BinaryMode mode(to_string(VoxelMode::solid_and_surface), VoxelMode::solid_and_surface,
                               "bits: both, the solid and every voxel the surface passes through");
  return mode;
}

}  // namespace voxd::api
