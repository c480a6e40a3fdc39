#pragma once
// The response headers that say what an analysis's bytes mean: the scale of
// a radiograph's pixel values (X-Voxd-Scale), a thickness volume's grid and
// unit (X-Voxd-Dims, -Origin, -Voxel-Size, -Unit).
#include <string>
#include <utility>
#include <vector>

#include "api/analysis_request.h"
#include "voxd/grid.h"

namespace voxd::server {

std::vector<std::pair<std::string, std::string>> analysis_headers(const api::AnalysisRequest& request, const Grid& grid);

}  // namespace voxd::server
