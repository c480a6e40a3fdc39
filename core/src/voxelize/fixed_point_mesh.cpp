#include "voxelize/fixed_point_mesh.h"

#include <cmath>

#include "voxd/error.h"

namespace voxd::detail {

FixedMesh::FixedMesh(const Mesh& mesh, const Grid& grid)
    : mesh_(&mesh), origin_(grid.origin), scale_(static_cast<double>(kFixedOne) / grid.voxel_size) {}

FixedPoint FixedMesh::vertex(std::uint32_t v) const {
  constexpr double half = 0.5 * static_cast<double>(kFixedOne);
  constexpr double limit = static_cast<double>(kFixedLimit);
  FixedPoint out;
  for (int a = 0; a < 3; ++a) {
    const double q = (static_cast<double>(mesh_->vertices[v][a]) - origin_[a]) * scale_ - half;
    if (!(std::fabs(q) < limit))
      throw Error(ErrorCode::invalid_argument,
                  "the mesh extends more than 2^40 voxels beyond the grid; use a grid that covers it");
    out[a] = static_cast<std::int64_t>(std::floor(q + 0.5));  // floor inlines, unlike llround
  }
  return out;
}

}  // namespace voxd::detail
