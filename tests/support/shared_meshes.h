#pragma once
// The real meshes of ../shared/meshes (VOXD_SHARED_MESHES, defined for each
// test target) and the grids the engine tests put around them.
#include <string>

#include "support/test_meshes.h"
#include "voxd/grid.h"
#include "voxd/mesh.h"
#include "voxd/mesh_io/mesh_decode.h"

namespace voxd::test {

inline Mesh shared_mesh(const std::string& name) {
  const std::string path = std::string(VOXD_SHARED_MESHES) + "/" + name;
  return decode_mesh(read_file(path), name);
}

// `resolution` voxels along the mesh's longest axis, `padding` more around.
inline Grid grid_for(const Mesh& mesh, std::int64_t resolution, std::int64_t padding) {
  GridRequest r;
  r.resolution = resolution;
  r.padding = padding;
  return resolve_grid(r, bounds(mesh));
}

}  // namespace voxd::test
