#pragma once
// JSON view of the manufacturing analysis (proto-schemas/analysis.schema.json):
// every length in model units (the mesh's own, stated in `unit`), region
// positions as model coordinates, counts in voxels alongside.
#include <optional>

#include <nlohmann/json.hpp>

#include "voxd/analysis/analysis.h"
#include "voxd/grid.h"
#include "voxd/analysis/mass_properties.h"
#include "voxd/mesh_report.h"

namespace voxd::api {

// At most this many parts, voids or regions are listed (largest first); the
// counts and totals always cover all of them.
inline constexpr std::size_t kMaxListedRegions = 100;

// `mesh` / `mesh_mass`: the uploaded mesh's report and exact properties, when
// known. An open mesh is reported as such instead of a meaningless volume.
nlohmann::json analysis_to_json(const AnalysisReport& report, const Grid& grid, const std::optional<MeshReport>& mesh,
                                const std::optional<MassProperties>& mesh_mass);

nlohmann::json to_json(const MassProperties& p);

}  // namespace voxd::api
