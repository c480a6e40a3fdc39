#include "api/job_mode.h"

#include "api/job_params.h"
#include "api/param_validator.h"
#include "api/result_json.h"
#include "voxd/error.h"

namespace voxd::api {

std::shared_ptr<ModeOptions> JobMode::parse_options(ParamValidator&, const nlohmann::json*, const JobParams&) const {
  return nullptr;
}

void JobMode::complete(ParamValidator&, const nlohmann::json&, JobParams&) const {}

std::optional<ValueVolume> JobMode::value_type(const JobParams&) const { return std::nullopt; }

glm::dvec3 JobMode::voxel_aspect(const JobParams&) const { return glm::dvec3(1.0); }

std::uint64_t JobMode::memory_estimate(const Grid& grid, const JobParams& params) const {
  return bit_volumes_memory(grid, voxel_mode(), params.inside);
}

bool JobMode::needs_parity_solid(const JobParams&) const { return false; }

std::optional<std::string> JobMode::streaming_refusal(const JobParams&) const {
  return "mode " + std::string(name()) + " makes values over the whole grid, so it runs in memory; only the modes of bits, coverage and the band sdf stream";
}

nlohmann::json JobMode::run_streamed(const ModeInput&, std::int64_t, const BitSlabConsumer&, const ValueSlabConsumer&) const {
  throw std::logic_error("mode " + std::string(name()) + " does not stream");
}

void JobMode::run_runs(const ModeInput&, const RunSlabConsumer&) const {
  throw std::logic_error("mode " + std::string(name()) + " does not make runs");
}

std::uint64_t JobMode::streamed_layer_bytes(const Grid& grid, const JobParams&) const {
  return bit_volume_bytes({grid.dims.x, grid.dims.y, 1});
}

std::string JobMode::values_content(const JobParams&) const { return "values"; }

std::string JobMode::layer_content(const std::string&, const nlohmann::json& values_info) const {
  return volume_content(values_info);
}

bool JobMode::writes(VolumeFormat) const { return false; }

void JobMode::write(VolumeFormat format, const JobParams&, const VolumeSource&, ByteSink&) const {
  throw Error(ErrorCode::invalid_argument, "mode " + std::string(name()) + " does not write " + to_string(format) + " itself");
}

std::shared_ptr<const ValueVolume> JobMode::layer(const std::string&, const JobParams&, const VolumeSource&) const {
  std::string what;
  for (const JobMode* m : job_modes()) {
    const std::vector<std::string> names = m->layer_names();
    if (names.empty()) continue;
    if (!what.empty()) what += "; ";
    what += "a " + std::string(m->name()) + " job's ";
    for (std::size_t i = 0; i < names.size(); ++i)
      what += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + names[i];
    what += " volume";
  }
  throw QueryRejected("layer selects " + what + "; this job's mode is " + std::string(name()));
}

nlohmann::json JobMode::document(const std::string& document, const JobParams&, const VolumeSource&) const {
  throw Error(ErrorCode::invalid_argument, "mode " + std::string(name()) + " has no document " + document);
}

std::optional<SdfRenderInput> JobMode::distance_field(const JobParams&, const ValueVolume&) const { return std::nullopt; }

const JobMode* find_job_mode(std::string_view name) {
  for (const JobMode* m : job_modes())
    if (m->name() == name) return m;
  return nullptr;
}

std::string modes_with(const std::function<bool(const JobMode&)>& has) {
  std::vector<std::string> names;
  for (const JobMode* m : job_modes())
    if (has(*m)) {
      std::string quoted = "\"";  // appended piecewise: GCC 12 warns falsely (-Wrestrict) on "\"" + s + "\""
      quoted.append(m->name()).append("\"");
      names.push_back(std::move(quoted));
    }
  std::string out;
  for (std::size_t i = 0; i < names.size(); ++i) out += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + names[i];
  return out;
}

void refuse_inside_test(ParamValidator& val, const nlohmann::json& job, std::string_view mode) {
  if (job.contains("inside"))
    val.fail("/inside", std::string(mode) + " counts crossings along rays (parity); the inside test does not apply to it");
}

std::uint64_t bit_volumes_memory(const Grid& grid, VoxelMode mode, InsideTest inside) {
  const std::uint64_t bits = static_cast<std::uint64_t>((grid.dims.x + 63) / 64) * 8 *
                             static_cast<std::uint64_t>(grid.dims.y) * static_cast<std::uint64_t>(grid.dims.z);
  std::uint64_t volumes = 1;
  if (mode != VoxelMode::surface && inside == InsideTest::vote) volumes = 3;
  if (mode == VoxelMode::solid_and_surface) volumes += 1;
  return bits * volumes;
}

}  // namespace voxd::api
