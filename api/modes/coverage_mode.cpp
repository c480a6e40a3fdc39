#include "api/modes/coverage_mode.h"

#include <nlohmann/json.hpp>

#include "api/job_params.h"
#include "api/param_validator.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd::api {
namespace {

using nlohmann::json;

void parse_coverage(ParamValidator& val, const json& c, CoverageParams& out) {
  const std::string path = "/coverage";
  if (!val.is_object(c, path)) return;
  val.allow_keys(c, path, {"sampling", "rays", "points", "seed", "threshold", "values"});
  if (auto s = val.one_of(c, path, "sampling", kCoverageSamplingNames)) out.options.sampling = *s;
  if (auto k = val.integer(c, path, "rays", 1, 64)) out.options.rays = static_cast<int>(*k);
  if (auto m = val.integer(c, path, "points", 1, 256)) out.options.points = static_cast<int>(*m);
  // Options that the chosen sampling would silently ignore are refused, so a
  // client never believes it set something it did not.
  if (c.contains("points") && out.options.sampling != CoverageSampling::uniform)
    val.fail(path + "/points", "points per voxel apply only to sampling \"uniform\" (the paper's point sampling); "
                               "\"exact\" and \"stochastic\" integrate along each ray exactly");
  if (c.contains("seed")) {
    const json& v = c.at("seed");
    if (!v.is_number_integer() || (v.is_number_integer() && !v.is_number_unsigned() && v.get<std::int64_t>() < 0))
      val.fail(path + "/seed", "must be a non-negative integer, got " + brief_json(v));
    else
      out.options.seed = v.get<std::uint64_t>();
    if (out.options.sampling != CoverageSampling::stochastic)
      val.fail(path + "/seed", "the seed applies only to sampling \"stochastic\" (the other samplings place rays regularly)");
  }
  if (auto t = val.number(c, path, "threshold", 0.0, 1.0, true)) out.threshold = static_cast<float>(*t);
  if (auto v = val.one_of(c, path, "values", {"u8", "f32"})) out.float_values = *v == "f32";
  if (c.contains("threshold") && c.contains("values"))
    val.fail(path + "/values", "with a threshold the volume is bits (coverage >= threshold); drop one of the two");
}

class CoverageMode final : public ModeWithOptions<CoverageParams> {
 public:
  std::string_view name() const override { return "coverage"; }
  std::string_view summary() const override {
    return "each voxel's share inside (Thon): bytes 0..255, \"values\": \"f32\" for fractions, bits with a threshold";
  }

  void parse(ParamValidator& val, const json* options, CoverageParams& out) const override {
    if (options) parse_coverage(val, *options, out);
  }

  void complete(ParamValidator& val, const json& job, JobParams&) const override {
    refuse_inside_test(val, job, name());
  }

  // The coverages (the bits of a threshold are made from them on the CPU).
  bool runs_on_gpu() const override { return true; }

  std::optional<ValueVolume> value_type(const JobParams& params) const override {
    const CoverageParams& c = options(params);
    if (c.threshold) return std::nullopt;
    if (c.float_values) return ValueVolume(DenseVolume<float>());
    return ValueVolume(DenseVolume<std::uint8_t>());
  }

  // Coverage is computed as one float per voxel; bytes are made from the
  // floats (both alive for a moment).
  std::uint64_t memory_estimate(const Grid& grid, const JobParams& params) const override {
    return bit_volumes_memory(grid, VoxelMode::solid, params.inside) + 4 * grid.voxel_count() +
           (options(params).float_values ? 0 : grid.voxel_count());
  }

  // The solid is the parity solid of its crossings; a threshold makes the
  // job's bits from the values instead.
  bool uses_inside_test() const override { return false; }
  bool needs_parity_solid(const JobParams& params) const override { return !options(params).threshold; }

  JobVolumes run(const ModeInput& in) const override {
    const CoverageParams& c = options(in.params);
    CoverageRunReport report;
    DenseVolume<float> coverage = voxelize_coverage(in.mesh, in.grid, engine_options(in), in.control, &report);
    JobVolumes result;
    result.values_info = values_info(c, covered_voxels(coverage, in.threads), in.grid, report);
    if (c.threshold)
      result.solid = std::make_shared<const BitVolume>(coverage_threshold(coverage, *c.threshold));
    else if (c.float_values)
      result.values = std::make_shared<const ValueVolume>(std::move(coverage));
    else
      result.values = std::make_shared<const ValueVolume>(coverage_bytes(coverage, in.threads));
    return result;
  }

  // Slab by slab (voxelize_coverage_streamed): the same values, bytes, bits
  // and covered volume as run(), one slab of floats at a time.
  std::optional<std::string> streaming_refusal(const JobParams&) const override { return std::nullopt; }

  nlohmann::json run_streamed(const ModeInput& in, std::int64_t slab_layers, const BitSlabConsumer& bits,
                              const ValueSlabConsumer& values) const override {
    const CoverageParams& c = options(in.params);
    CoveredVoxels covered;
    CoverageRunReport report;
    voxelize_coverage_streamed(in.mesh, in.grid, engine_options(in), slab_layers,
                               [&](std::int64_t k0, const DenseVolume<float>& slab) {
                                 covered.add(slab, in.threads);
                                 if (c.threshold)
                                   bits(k0, coverage_threshold(slab, *c.threshold));
                                 else if (c.float_values)
                                   values(k0, ValueVolume(slab));
                                 else
                                   values(k0, ValueVolume(coverage_bytes(slab, in.threads)));
                               },
                               in.control, &report);
    return values_info(c, covered.total(), in.grid, report);
  }

  // A slab's floats, and beside them its bytes or bits, or the floats' copy
  // handed on as values.
  std::uint64_t streamed_layer_bytes(const Grid& grid, const JobParams& params) const override {
    const std::uint64_t voxels = static_cast<std::uint64_t>(grid.dims.x) * static_cast<std::uint64_t>(grid.dims.y);
    const CoverageParams& c = options(params);
    return 4 * voxels + (c.threshold ? bit_volume_bytes({grid.dims.x, grid.dims.y, 1}) : c.float_values ? 4 * voxels : voxels);
  }

  std::string values_content(const JobParams& params) const override {
    return std::string("coverage (") + unit(options(params)) + ")";
  }

 private:
  static const char* unit(const CoverageParams& c) {
    return c.float_values ? "fraction of the voxel" : "fraction of the voxel x 255";
  }

  static CoverageOptions engine_options(const ModeInput& in) {
    CoverageOptions o = options(in.params).options;
    o.threads = in.threads;
    o.device = in.params.device.value_or(ComputeDevice::automatic);
    return o;
  }

  static nlohmann::json values_info(const CoverageParams& c, double covered, const Grid& grid,
                                    const CoverageRunReport& report) {
    json info = {{"quantity", "coverage"},
                 {"sampling", to_string(c.options.sampling)},
                 {"covered_volume", covered * grid.voxel_volume()},
                 {"device", to_string(report.device)}};
    if (c.threshold)
      info["threshold"] = *c.threshold;
    else
      info["unit"] = unit(c);
    return info;
  }
};

}  // namespace

const JobMode& coverage_mode() {
  static const CoverageMode mode;
  return mode;
}

}  // namespace voxd::api
