#pragma once
// The job parameters JSON (proto-schemas/job-params.schema.json), shared by the
// CLI and the HTTP API, parsed into engine types.
#include <optional>
#include <string>
#include <vector>

#include <glm/mat3x3.hpp>
#include <nlohmann/json_fwd.hpp>

#include "api/analysis_request.h"
#include "voxd/grid.h"
#include "voxd/voxelize.h"

namespace voxd::api {

struct JobParams {
  GridRequest grid;
  std::optional<glm::dmat3> rotation;  // applied before orient
  bool orient_auto = false;
  VoxelMode mode = VoxelMode::solid;
  InsideTest inside = InsideTest::parity;
  // Analyses the worker prepares once the volume exists (api/analysis_request.h).
  std::vector<AnalysisRequest> analyses;
};

// Validates and converts. Unknown keys, wrong types and out-of-range values
// are all reported together in InvalidParams.
JobParams parse_job_params(const nlohmann::json& params);
// Parses text first; malformed JSON is reported as an InvalidParams at path "".
JobParams parse_job_params_text(const std::string& text);

}  // namespace voxd::api
