#include "voxelize/fixed_point_mesh.h"

#include <cmath>

#include "voxd/error.h"

namespace voxd::detail {

FixedMesh::FixedMesh(const Mesh& mesh, const Grid& grid)
    : mesh_(&mesh), origin_(grid.origin), scale_(static_cast<double>(kFixedOne) / grid.voxel_size) {}

void FixedMesh::throw_far_vertex() {
  throw Error(ErrorCode::invalid_argument,
              "the mesh extends more than 2^40 voxels beyond the grid; use a grid that covers it");
}

}  // namespace voxd::detail
