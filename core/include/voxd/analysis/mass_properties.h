#pragma once
// Mass properties of a part at unit density: volume, centroid and the inertia
// tensor about the centroid (multiply by the material density for kg·m²).
// Computed exactly from a closed mesh (divergence theorem over signed
// tetrahedra) and from a voxel model (each filled voxel a full cube), so a
// client can see both side by side and how far the voxel model is off.
#include <cstdint>
#include <memory>

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include "voxd/bit_volume.h"
#include "voxd/mesh.h"
#include "voxd/run_slab.h"

namespace voxd {

struct MassProperties {
  double volume = 0.0;
  glm::dvec3 centroid{0.0};
  // Inertia tensor about the centroid, axes of the model: diagonal entries
  // are the moments (∫ y²+z² dV ...), off-diagonal ones the products with
  // the conventional minus sign (−∫ xy dV ...).
  glm::dmat3 inertia{0.0};
  Aabb bbox;
};

// Exact for a closed, consistently oriented mesh; for an open mesh the result
// depends on where the origin lies and means nothing (callers check the mesh
// report's `watertight` first). An inside-out mesh gives a negative volume.
MassProperties mesh_mass_properties(const Mesh& mesh);

// Sum over filled voxels of the cube each occupies (including each cube's own
// inertia, h²/12 per axis), in model units. Multithreaded over slabs.
MassProperties voxel_mass_properties(const BitVolume& volume, int threads = 0);

// voxel_mass_properties of a volume that arrives slab by slab (a streamed
// voxelization, a stored result replayed from its RLE): add() every slab of
// the grid once, in any order, then result(). The sums are exact integers of
// voxel indices, so the result is the same for any slabs and threads, and
// voxel_mass_properties is the one-slab case.
class VoxelMassAccumulator {
 public:
  explicit VoxelMassAccumulator(const Grid& grid);
  ~VoxelMassAccumulator();
  VoxelMassAccumulator(const VoxelMassAccumulator&) = delete;
  VoxelMassAccumulator& operator=(const VoxelMassAccumulator&) = delete;

  // Layers [k0, k0 + slab.grid().dims.z) of the grid.
  void add(std::int64_t k0, const BitVolume& slab, int threads = 0);
  // The same layers as runs (a stored result read as its runs).
  void add(std::int64_t k0, const RunSlab& slab, int threads = 0);
  MassProperties result() const;

 private:
  struct Sums;
  Grid grid_;
  std::unique_ptr<Sums> sums_;
};

}  // namespace voxd
