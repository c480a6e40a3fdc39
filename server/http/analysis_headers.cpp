#include "server/http/analysis_headers.h"

#include <cstdio>

#include "server/jobs/job_analyses.h"

namespace voxd::server {

using api::AnalysisKind;
using api::AnalysisRequest;

std::vector<std::pair<std::string, std::string>> analysis_headers(const AnalysisRequest& r, const Grid& grid) {
  auto scale = [](double per_value, const std::string& unit) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.17g", per_value);
    return std::string("1 pixel value = ") + buf + " " + unit;
  };
  switch (r.kind) {
    case AnalysisKind::radiography: {
      const PngScale s = radiography_scale(r, grid);
      return {{"X-Voxd-Scale", scale(s.per_value, s.unit)}};
    }
    case AnalysisKind::thickness: {
      char dims[96];
      std::snprintf(dims, sizeof dims, "%lld %lld %lld", static_cast<long long>(grid.dims.x),
                    static_cast<long long>(grid.dims.y), static_cast<long long>(grid.dims.z));
      char origin[128];
      std::snprintf(origin, sizeof origin, "%.17g %.17g %.17g", grid.origin.x, grid.origin.y, grid.origin.z);
      char size[40];
      std::snprintf(size, sizeof size, "%.17g", grid.voxel_size);
      return {{"X-Voxd-Dims", dims}, {"X-Voxd-Origin", origin}, {"X-Voxd-Voxel-Size", size},
              {"X-Voxd-Unit", r.unit == "model" ? "model units" : "voxels"}};
    }
    default: return {};
  }
}

}  // namespace voxd::server
