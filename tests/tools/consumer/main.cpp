// Decodes a mesh, voxelizes it solid on an explicit grid and prints what a
// caller would check: the triangle count, the filled voxels and the mesh's
// exact volume. Includes the umbrella header, so every installed public
// header must compile on its own, without the source tree.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <vector>

#include "voxd/voxd.h"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: voxd_consumer MESH VOXEL_SIZE\n");
    return 2;
  }
  std::ifstream in(argv[1], std::ios::binary);
  const std::vector<std::uint8_t> bytes{std::istreambuf_iterator<char>(in), {}};
  try {
    const voxd::Mesh mesh = voxd::decode_mesh(bytes, argv[1]);
    // An explicit grid: one empty voxel of margin around the mesh's box.
    const double h = std::atof(argv[2]);
    const voxd::Aabb box = voxd::bounds(mesh);
    voxd::GridRequest request;
    request.kind = voxd::GridRequest::Kind::explicit_grid;
    request.voxel_size = h;
    request.origin = glm::dvec3(box.min) - h;
    for (int a = 0; a < 3; ++a) request.dims[a] = static_cast<std::int64_t>(std::ceil((box.max[a] - box.min[a]) / h)) + 2;
    const voxd::Grid grid = voxd::resolve_grid(request, box);
    const voxd::BitVolume solid = voxd::voxelize(mesh, grid, voxd::VoxelizeOptions{});
    std::printf("triangles %zu\nfilled %llu\nmesh_volume %.6f\n", mesh.triangles.size(),
                static_cast<unsigned long long>(solid.count()), voxd::mesh_mass_properties(mesh).volume);
  } catch (const voxd::Error& e) {
    std::fprintf(stderr, "voxd_consumer: %s\n", e.what());
    return 1;
  }
  return 0;
}
