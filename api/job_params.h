#pragma once
// The job parameters JSON (proto-schemas/job-params.schema.json), shared by the
// CLI and the HTTP API, parsed into engine types.
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <glm/mat3x3.hpp>
#include <nlohmann/json_fwd.hpp>

#include "api/analysis_request.h"
#include "api/job_mode.h"
#include "api/length_unit.h"
#include "voxd/compute_device.h"
#include "voxd/encode/volume_format.h"
#include "voxd/grid.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd::api {

// Whether a job's volume is made slab by slab and kept as its RLE (grids
// past memory) or made whole in memory: auto decides from the grid.
enum class Streaming { automatic, on, off };
inline constexpr EnumNames<Streaming, 3> kStreamingNames{
    {{Streaming::automatic, "auto"}, {Streaming::on, "on"}, {Streaming::off, "off"}}};
inline const char* to_string(Streaming s) noexcept { return name_of(kStreamingNames, s); }

struct JobParams {
  GridRequest grid;
  std::optional<glm::dmat3> rotation;  // applied before orient
  bool orient_auto = false;
  // The job's mode (api/job_mode.h), recorded once here: whatever needs to
  // know what the job makes asks it. Never null.
  const JobMode* mode = nullptr;
  // The inside test of the job's solid (the result of a solid job, the solid
  // the analyses measure for a value job), also the sign of a distance field.
  // With inside_auto ("inside": "auto", the default) it is chosen from the
  // mesh when the job is prepared (api/inside_choice.h) and set here then;
  // until then it reads parity.
  InsideTest inside = InsideTest::parity;
  bool inside_auto = true;
  // The mesh file's unit; everything after reading it is in millimetres.
  LengthUnit units = LengthUnit::mm;
  // The mode's options (the object under its name), parsed by the mode; may be null.
  std::shared_ptr<ModeOptions> options;
  // Analyses the worker prepares once the volume exists (api/analysis_request.h).
  std::vector<AnalysisRequest> analyses;
  Streaming streaming = Streaming::automatic;
  // "device": where what a GPU can compute runs (the mode's run reads it);
  // unset, the service's own, which preparing the job fills in.
  std::optional<ComputeDevice> device;

  JobParams();
  // The job's "mode" as written (api/modes/mode_registry.cpp lists them).
  std::string mode_name() const { return std::string(mode->name()); }
  // Whether the job's result is a volume of values (u8, f32 or rgba8) rather than bits.
  bool has_values() const { return value_type().has_value(); }
  // An empty volume of the value type the job produces, to ask
  // format_refusal() before any work; nullopt for a job of bits.
  std::optional<ValueVolume> value_type() const { return mode->value_type(*this); }
  // Why the job's result cannot be given in `format` with `options` (a
  // format the mode writes itself, or one its bits or values take, is
  // none): what GET /v1/jobs/{id}/volume refuses, and the job status's
  // downloads leave out.
  std::optional<std::string> format_refusal(VolumeFormat format, const EncodeOptions& options = {}) const {
    if (mode->writes(format)) return std::nullopt;
    const std::optional<ValueVolume> probe = value_type();
    return probe ? voxd::format_refusal(*probe, format, options) : voxd::format_refusal(BitVolume(), format);
  }
  // The mode's options as its own type; null for another mode's.
  template <class T>
  const T* options_as() const {
    return dynamic_cast<const T*>(options.get());
  }
};

template <class Options>
const Options& ModeWithOptions<Options>::options(const JobParams& params) {
  return *params.template options_as<Options>();
}

template <class Options>
Options& ModeWithOptions<Options>::options(JobParams& params) {
  return const_cast<Options&>(options(static_cast<const JobParams&>(params)));
}

// Validates and converts. Unknown keys, wrong types and out-of-range values
// are all reported together in InvalidParams.
JobParams parse_job_params(const nlohmann::json& params);
// Parses text first; malformed JSON is reported as an InvalidParams at path "".
JobParams parse_job_params_text(const std::string& text);

}  // namespace voxd::api
