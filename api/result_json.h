#pragma once
// JSON views of engine results (mesh report, grid, timings), as published in
// the schemas of proto-schemas/ and shared by the CLI and the HTTP API.
#include <nlohmann/json.hpp>

#include "voxd/grid.h"
#include "voxd/mesh_report.h"

namespace voxd::api {

nlohmann::json to_json(const MeshReport& report);
nlohmann::json to_json(const Grid& grid);

}  // namespace voxd::api
