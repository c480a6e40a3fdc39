#include "voxelize/fixed_point_mesh.h"

#include <cmath>

#include "voxd/error.h"
#include "voxd/parallel.h"

namespace voxd::detail {

FixedMesh quantize_mesh(const Mesh& mesh, const Grid& grid, int threads) {
  FixedMesh out;
  out.triangles = &mesh.triangles;
  out.vertices.resize(mesh.vertices.size());
  const double scale = static_cast<double>(kFixedOne) / grid.voxel_size;
  const double limit = static_cast<double>(kFixedLimit);
  parallel_for(0, static_cast<std::int64_t>(mesh.vertices.size()), 1 << 16, threads,
               [&](std::int64_t b, std::int64_t e) {
                 for (std::int64_t v = b; v < e; ++v) {
                   for (int a = 0; a < 3; ++a) {
                     const double q = (static_cast<double>(mesh.vertices[v][a]) - grid.origin[a]) * scale -
                                      0.5 * static_cast<double>(kFixedOne);
                     if (!(std::fabs(q) < limit))
                       throw Error(ErrorCode::invalid_argument,
                                   "the mesh extends more than 2^40 voxels beyond the grid; use a grid that covers it");
                     out.vertices[v][a] = static_cast<std::int64_t>(std::floor(q + 0.5));  // inlines, unlike llround
                   }
                 }
               });
  return out;
}

}  // namespace voxd::detail
