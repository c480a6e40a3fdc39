#include "voxd/voxelize/voxelize.h"

#include "voxd/error.h"

namespace voxd {

namespace {

BitVolume voxelize_solid(const Mesh& mesh, const Grid& grid, const VoxelizeOptions& options, JobControl* control) {
  switch (options.inside) {
    case InsideTest::parity: return voxelize_parity(mesh, grid, 0, options.threads, control);
    case InsideTest::vote: return voxelize_vote(mesh, grid, options.threads, control);
    case InsideTest::winding: return voxelize_winding(mesh, grid, options.threads, control);
  }
  throw Error(ErrorCode::invalid_argument, "unknown inside test");
}

}  // namespace

BitVolume voxelize(const Mesh& mesh, const Grid& grid, const VoxelizeOptions& options, JobControl* control) {
  switch (options.mode) {
    case VoxelMode::solid: return voxelize_solid(mesh, grid, options, control);
    case VoxelMode::surface: return voxelize_surface(mesh, grid, options.threads, control);
    case VoxelMode::solid_and_surface: {
      // Walls thinner than a voxel can miss every centre; the surface shell keeps them.
      BitVolume solid = voxelize_solid(mesh, grid, options, control);
      solid.merge_or(voxelize_surface(mesh, grid, options.threads, control));
      return solid;
    }
  }
  throw Error(ErrorCode::invalid_argument, "unknown voxel mode");
}

}  // namespace voxd
