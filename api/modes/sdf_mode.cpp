#include "api/modes/sdf_mode.h"

#include <algorithm>
#include <limits>

#include <nlohmann/json.hpp>

#include "api/job_params.h"
#include "api/param_validator.h"
#include "api/result_json.h"
#include "voxd/compute_device.h"

namespace voxd::api {
namespace {

using nlohmann::json;

void parse_sdf(ParamValidator& val, const json& d, SdfOptions& out) {
  const std::string path = "/sdf";
  if (!val.is_object(d, path)) return;
  val.allow_keys(d, path, {"band", "sign_convention", "units"});
  if (d.contains("band")) {
    const json& b = d.at("band");
    if (b.is_string()) {
      if (b.get<std::string>() == "full")
        out.full = true;
      else
        val.fail(path + "/band", "must be a number of voxels (> 0 and <= 1000) or \"full\", got " + brief_json(b));
    } else if (auto w = val.number(d, path, "band", 0.0, 1000.0, true)) {
      out.band = *w;
    }
  }
  if (auto s = val.one_of(d, path, "sign_convention", kSignConventionNames)) out.sign = *s;
  if (auto u = val.one_of(d, path, "units", {"model", "voxels"})) out.model_units = *u == "model";
}

// The smallest and largest value. A plain loop the compiler turns into
// packed min/max (minmax_element's positions keep it scalar: a tenth of a
// second at 512^3); a field holds no NaN and no -0, so no order question.
std::pair<float, float> value_range(const DenseVolume<float>& values) {
  float lo = std::numeric_limits<float>::infinity(), hi = -lo;
  for (const float v : values.values()) {
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  return {lo, hi};
}

// The job status's "values" (proto-schemas/job-status.schema.json).
json values_info(const SdfOptions& o, float lo, float hi) {
  return {{"quantity", "signed distance"},
          {"unit", o.model_units ? "model units" : "voxels"},
          {"sign_convention", to_string(o.sign)},
          {"band", o.full ? json("full") : json(o.band)},
          {"min", lo},
          {"max", hi}};
}

class SdfMode final : public ModeWithOptions<SdfParams> {
  // The engine's options: the job's, signed by the job's inside test (which
  // "inside": "auto" resolves only once the mesh is read).
  static SdfOptions engine_options(const JobParams& params) {
    SdfOptions o = options(params);
    o.inside = params.inside;
    o.device = params.device.value_or(ComputeDevice::automatic);
    return o;
  }

 public:
  std::string_view name() const override { return "sdf"; }
  std::string_view summary() const override {
    return "signed distance to the surface (Jones): float32 (rle, raw or nrrd; binvox holds no floats)";
  }
  // The sign comes from the job's inside test.
  void parse(ParamValidator& val, const json* options, SdfParams& out) const override {
    if (options) parse_sdf(val, *options, out);
  }

  std::optional<ValueVolume> value_type(const JobParams&) const override { return ValueVolume(DenseVolume<float>()); }

  // The band; the solid that signs it is made on the CPU.
  bool runs_on_gpu() const override { return true; }

  // One float per voxel; the field holds its own solid for the sign beside the job's.
  std::uint64_t memory_estimate(const Grid& grid, const JobParams& params) const override {
    return bit_volumes_memory(grid, VoxelMode::solid, params.inside) +
           bit_volumes_memory(grid, VoxelMode::solid, InsideTest::parity) + 4 * grid.voxel_count();
  }

  // The field hands back the solid that signs it: the job's bits.
  JobVolumes run(const ModeInput& in) const override {
    SdfOptions o = engine_options(in.params);
    o.threads = in.threads;
    JobVolumes result;
    BitVolume solid;
    DeviceRunReport report;
    DenseVolume<float> sdf = signed_distance_field(in.mesh, in.grid, o, in.control, &solid, &report);
    result.solid = std::make_shared<const BitVolume>(std::move(solid));
    const auto [lo, hi] = value_range(sdf);
    result.values_info = values_info(o, lo, hi);
    result.values_info["device"] = to_string(report.device);
    result.values = std::make_shared<const ValueVolume>(std::move(sdf));
    return result;
  }

  // The band goes slab by slab (signed_distance_field_slabs): a whole
  // grid's floats are never held, and their fresh pages never cleared.
  std::optional<std::string> streaming_refusal(const JobParams& params) const override {
    return sdf_slabs_refusal(engine_options(params));
  }
  // Unless a GPU may take the band: it makes the whole grid's at once.
  bool faster_in_slabs(const JobParams& params) const override {
    const bool gpu = params.device.value_or(ComputeDevice::automatic) == ComputeDevice::automatic &&
                     cuda_unavailable_reason().empty();
    return !streaming_refusal(params) && !gpu;
  }

  nlohmann::json run_streamed(const ModeInput& in, std::int64_t, const BitSlabConsumer& bits,
                              const ValueSlabConsumer& values) const override {
    SdfOptions o = engine_options(in.params);
    o.threads = in.threads;
    float lo = std::numeric_limits<float>::infinity(), hi = -lo;
    signed_distance_field_slabs(
        in.mesh, in.grid, o, [&](std::int64_t k0, const RunSlab& solid) { bits(k0, solid.to_bits()); },
        [&](std::int64_t k0, const ValueVolume& slab) {
          const auto [l, h] = value_range(std::get<DenseVolume<float>>(slab));
          lo = std::min(lo, l);
          hi = std::max(hi, h);
          values(k0, slab);
        },
        in.control);
    json info = values_info(o, lo, hi);
    info["device"] = to_string(ComputeDevice::cpu);
    return info;
  }

  // What a streamed NRRD's header says, before the values exist: what the
  // in-memory one's says from them.
  std::string values_content(const JobParams& params) const override {
    return volume_content(values_info(options(params), 0.0f, 0.0f));
  }

  // A slab's floats (the solid's runs are a few bytes a row).
  std::uint64_t streamed_layer_bytes(const Grid& grid, const JobParams&) const override {
    return 4 * static_cast<std::uint64_t>(grid.dims.x) * static_cast<std::uint64_t>(grid.dims.y);
  }

  bool distance_values() const override { return true; }
  std::optional<SdfRenderInput> distance_field(const JobParams& params, const ValueVolume& values) const override {
    return sdf_render_input(std::get<DenseVolume<float>>(values), options(params));
  }
};

}  // namespace

const JobMode& sdf_mode() {
  static const SdfMode mode;
  return mode;
}

}  // namespace voxd::api
