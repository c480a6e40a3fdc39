#pragma once
// Binary voxelization: solid (centre-inside test), surface (conservative
// triangle/voxel overlap) and their union.
#include "voxd/bit_volume.h"
#include "voxd/grid.h"
#include "voxd/mesh.h"
#include "voxd/progress.h"
#include "voxd/enum_names.h"

namespace voxd {

enum class VoxelMode { solid, surface, solid_and_surface };
enum class InsideTest {
  parity,   // crossings along x per column (Thon et al.; Patil & Ravi)
  vote,     // parity along x, y and z, majority of the three (Nooruddin & Turk)
  winding,  // generalized winding number >= 1/2 (Jacobson et al. 2013)
};

inline constexpr EnumNames<VoxelMode, 3> kVoxelModeNames{{
    {VoxelMode::solid, "solid"}, {VoxelMode::surface, "surface"}, {VoxelMode::solid_and_surface, "solid+surface"}}};
inline constexpr EnumNames<InsideTest, 3> kInsideTestNames{{
    {InsideTest::parity, "parity"}, {InsideTest::vote, "vote"}, {InsideTest::winding, "winding"}}};
inline const char* to_string(VoxelMode mode) noexcept { return name_of(kVoxelModeNames, mode); }
inline const char* to_string(InsideTest inside) noexcept { return name_of(kInsideTestNames, inside); }

struct VoxelizeOptions {
  VoxelMode mode = VoxelMode::solid;
  InsideTest inside = InsideTest::parity;
  int threads = 0;  // 0 = all cores
};

// Voxelizes `mesh` (in grid model coordinates) into `grid`. `control` may be
// null; when given, progress is reported and cancellation honoured.
BitVolume voxelize(const Mesh& mesh, const Grid& grid, const VoxelizeOptions& options,
                   JobControl* control = nullptr);

// The individual methods, for callers and tests that want one directly.
BitVolume voxelize_parity(const Mesh& mesh, const Grid& grid, int axis, int threads, JobControl* control);
BitVolume voxelize_vote(const Mesh& mesh, const Grid& grid, int threads, JobControl* control);
BitVolume voxelize_winding(const Mesh& mesh, const Grid& grid, int threads, JobControl* control);
BitVolume voxelize_surface(const Mesh& mesh, const Grid& grid, int threads, JobControl* control);

}  // namespace voxd
