#pragma once
// The job parameters JSON (proto-schemas/job-params.schema.json), shared by the
// CLI and the HTTP API, parsed into engine types.
#include <optional>
#include <string>
#include <vector>

#include <glm/mat3x3.hpp>
#include <nlohmann/json_fwd.hpp>

#include "api/analysis_request.h"
#include "voxd/voxelize/coverage.h"
#include "voxd/grid.h"
#include "voxd/voxelize/palette.h"
#include "voxd/voxelize/palette_render.h"
#include "voxd/voxelize/sdf.h"
#include "voxd/voxelize/slice_functions.h"
#include "voxd/encode/volume_format.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd::api {

// "mode": "coverage" (Thon et al.'s grey levels) and its "coverage" object.
struct CoverageParams {
  CoverageOptions options;          // sampling, rays, points, seed (threads set by the runner)
  std::optional<float> threshold;   // set: the job's volume is the bits coverage >= threshold
  bool float_values = false;        // "values": "f32" (fractions 0..1) instead of "u8" (Thon's byte)
};

// "mode": "palette" (Cavagnino & Gribaudo) and its "palette" object.
struct PaletteParams {
  PaletteOptions options;              // palette, metric, rays, points, seed (threads set by the runner)
  std::string palette_name = "46";     // "2", "10", "46", "78" or "custom"
  glm::dvec3 voxel_aspect{1.0};        // the voxel's edges over the grid's voxel_size (anisotropic voxels)
  RenderPalette render;                // display objects by element and similarity (may be empty)
};

struct JobParams {
  GridRequest grid;
  std::optional<glm::dmat3> rotation;  // applied before orient
  bool orient_auto = false;
  // The binary volume: the result of a solid/surface job, and the solid
  // (centre inside) that the analyses measure for a coverage or sdf job.
  VoxelMode mode = VoxelMode::solid;
  InsideTest inside = InsideTest::parity;  // also the sign of an sdf job
  std::optional<CoverageParams> coverage;  // set iff "mode": "coverage"
  std::optional<SdfOptions> sdf;           // set iff "mode": "sdf" (inside = the job's inside)
  std::optional<PaletteParams> palette;    // set iff "mode": "palette"
  std::optional<SliceOptions> slice;       // set iff "mode": "slice" (inside = the job's inside)

  // The job's "mode" as written: solid, surface, solid+surface, coverage, sdf, palette, slice.
  std::string mode_name() const;
  // Whether the job's result is a volume of values (u8, f32 or rgba8) rather than bits.
  bool has_values() const { return sdf || palette || slice || (coverage && !coverage->threshold); }
  // Analyses the worker prepares once the volume exists (api/analysis_request.h).
  std::vector<AnalysisRequest> analyses;
};

// An empty volume of the value type a value job produces (u8, f32 or
// rgba8), to ask format_refusal() before any work; nullopt for a job of bits.
std::optional<ValueVolume> value_type_probe(const JobParams& params);

// Validates and converts. Unknown keys, wrong types and out-of-range values
// are all reported together in InvalidParams.
JobParams parse_job_params(const nlohmann::json& params);
// Parses text first; malformed JSON is reported as an InvalidParams at path "".
JobParams parse_job_params_text(const std::string& text);

}  // namespace voxd::api
