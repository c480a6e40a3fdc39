#pragma once
// JSON views of engine results (mesh report, grid, timings), as published in
// the schemas of proto-schemas/ and shared by the CLI and the HTTP API.
#include <string>

#include <nlohmann/json.hpp>

#include "voxd/grid.h"
#include "voxd/mesh_report.h"

namespace voxd::api {

nlohmann::json to_json(const MeshReport& report);
nlohmann::json to_json(const OrientationRepair& repair);
nlohmann::json to_json(const Grid& grid);

// What a volume's values are in words, from the job's "values" (null for a
// volume of bits): NRRD's "content:" field, the same from the CLI and the
// service. E.g. "signed distance (model units, inside_negative)".
std::string volume_content(const nlohmann::json& values_info);

}  // namespace voxd::api
