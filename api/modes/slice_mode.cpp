// "mode": "slice" (multi-valued voxelization by slice functions, after
// Liao; voxd/voxelize/slice_functions.h): an RGBA colour per voxel from a
// function of its position. Options under "slice", which needs "function".
#include <nlohmann/json.hpp>

#include "api/job_mode.h"
#include "api/job_params.h"
#include "api/param_validator.h"
#include "api/slice_options.h"
#include "voxd/error.h"
#include "voxd/voxelize/slice_functions.h"

namespace voxd::api {
namespace {

using nlohmann::json;

struct SliceParams : ModeOptions, SliceOptions {};

class SliceMode final : public ModeWithOptions<SliceParams> {
 public:
  std::string_view name() const override { return "slice"; }
  std::string_view summary() const override {
    return "an RGBA colour per voxel from a slice function (needs \"function\"): vox, png-stack, rle or raw";
  }
  // Which voxels are coloured is the job's inside test.
  void parse(ParamValidator& val, const json* options, SliceParams& out) const override {
    if (options)
      parse_slice_options(val, *options, "/slice", out);
    else
      val.fail("/slice", "required with mode \"slice\": at least {\"function\": ...}");
  }

  // The colours; the solid they colour is made on the CPU.
  bool runs_on_gpu() const override { return true; }

  std::optional<ValueVolume> value_type(const JobParams&) const override { return ValueVolume(DenseVolume<Rgba8>()); }
  bool colour_values() const override { return true; }

  // Four bytes a voxel beside the solid it colours.
  std::uint64_t memory_estimate(const Grid& grid, const JobParams& params) const override {
    return bit_volumes_memory(grid, VoxelMode::solid, params.inside) +
           bit_volumes_memory(grid, VoxelMode::solid, InsideTest::parity) + 4 * grid.voxel_count();
  }

  JobVolumes run(const ModeInput& in) const override {
    JobVolumes result;
    SliceOptions o = options(in.params);
    o.inside = in.params.inside;
    o.threads = in.threads;
    o.device = in.params.device.value_or(ComputeDevice::automatic);
    SliceRunReport report;
    DenseVolume<Rgba8> colours = voxelize_slice(in.mesh, in.grid, o, in.control, &report);
    // The solid is exactly the coloured voxels (alpha > 0).
    BitVolume solid(in.grid);
    for (std::int64_t k = 0; k < in.grid.dims.z; ++k)
      for (std::int64_t j = 0; j < in.grid.dims.y; ++j) {
        const Rgba8* row = colours.slab(k) + j * in.grid.dims.x;
        std::uint64_t* bits = solid.row(j, k);
        for (std::int64_t i = 0; i < in.grid.dims.x; ++i)
          if (row[i].a > 0) bits[i >> 6] |= std::uint64_t{1} << (i & 63);
      }
    result.solid = std::make_shared<const BitVolume>(std::move(solid));
    const SliceFrame frame = make_slice_frame(in.mesh, o.axis);
    result.values_info = {{"quantity", "colour"},
                          {"unit", "rgba8"},
                          {"function", to_string(o.function)},
                          {"axis", {frame.w.x, frame.w.y, frame.w.z}},
                          {"device", to_string(report.device)}};
    result.values = std::make_shared<const ValueVolume>(std::move(colours));
    return result;
  }
};

}  // namespace

const JobMode& slice_mode() {
  static const SliceMode mode;
  return mode;
}

}  // namespace voxd::api
