#include "api/modes/sdf_mode.h"

#include <algorithm>

#include <nlohmann/json.hpp>

#include "api/job_params.h"
#include "api/param_validator.h"

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

class SdfMode final : public ModeWithOptions<SdfParams> {
 public:
  std::string_view name() const override { return "sdf"; }
  std::string_view summary() const override {
    return "signed distance to the surface (Jones): float32 (rle, raw or nrrd; binvox holds no floats)";
  }
  // The sign comes from the job's inside test.
  void parse(ParamValidator& val, const json* options, SdfParams& out) const override {
    if (options) parse_sdf(val, *options, out);
  }

  void complete(ParamValidator&, const json&, JobParams& params) const override {
    options(params).inside = params.inside;
  }

  std::optional<ValueVolume> value_type(const JobParams&) const override { return ValueVolume(DenseVolume<float>()); }

  // One float per voxel; the field holds its own solid for the sign beside the job's.
  std::uint64_t memory_estimate(const Grid& grid, const JobParams& params) const override {
    return bit_volumes_memory(grid, VoxelMode::solid, params.inside) +
           bit_volumes_memory(grid, VoxelMode::solid, InsideTest::parity) + 4 * grid.voxel_count();
  }

  // The field hands back the solid that signs it: the job's bits.
  ModeResult run(const ModeInput& in) const override {
    SdfOptions o = options(in.params);
    o.threads = in.threads;
    ModeResult result;
    result.volume.emplace();
    DenseVolume<float> sdf = signed_distance_field(in.mesh, in.grid, o, in.control, &*result.volume);
    const auto [lo, hi] = std::minmax_element(sdf.values().begin(), sdf.values().end());
    result.values_info = {{"quantity", "signed distance"},
                          {"unit", o.model_units ? "model units" : "voxels"},
                          {"sign_convention", to_string(o.sign)},
                          {"band", o.full ? json("full") : json(o.band)},
                          {"min", *lo},
                          {"max", *hi}};
    result.values = std::move(sdf);
    return result;
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
