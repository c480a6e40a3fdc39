#pragma once
// Connected solid parts and enclosed voids of a voxel model. Manufacturing
// users ask "is this one part?" and "is there trapped powder, resin or
// porosity?". Digital topology needs complementary connectivities so a thin
// diagonal wall neither leaks nor merges: solids are 26-connected (voxels
// touching by a face, an edge or a corner belong together) and empty space is
// 6-connected (a void leaking only through an edge or a corner is still
// enclosed: powder cannot pass through a zero-width gap).
#include <cstdint>
#include <memory>
#include <vector>

#include <glm/vec3.hpp>

#include "voxd/bit_volume.h"
#include "voxd/run_slab.h"

namespace voxd {

struct VoxelRegion {
  std::uint64_t voxels = 0;
  glm::i64vec3 bbox_min{0}, bbox_max{0};  // voxel indices, inclusive
  glm::dvec3 centroid{0.0};               // mean voxel index (add 0.5 for the centre's offset)
};

struct ComponentReport {
  std::vector<VoxelRegion> parts;  // largest first
  std::vector<VoxelRegion> voids;  // empty regions not connected to the grid's outside, largest first
};

// Runs are labelled row by row with a union-find over runs, so memory is
// proportional to the number of runs, not voxels. Empty voxels on the grid's
// border are connected to the outside.
// `threads`: the runs of a batch of layers are found in parallel, and the
// two phases (parts, voids) are labelled on a thread each, past two threads
// each cut into runs of layers labelled apart and then joined (0 = all
// cores); the result, order included, is the same for any count.
ComponentReport find_components(const BitVolume& volume, int threads = 0);

// find_components of a volume that arrives slab by slab in z order (a
// streamed voxelization, a stored result replayed from its RLE): add() every
// slab, then finish(). A region is final as soon as no run of the current
// layer continues it, so memory is two layers' runs and the regions found,
// whatever nz is; find_components is the one-slab case.
class ComponentLabeller {
 public:
  explicit ComponentLabeller(const Grid& grid, int threads = 0);
  ~ComponentLabeller();
  ComponentLabeller(const ComponentLabeller&) = delete;
  ComponentLabeller& operator=(const ComponentLabeller&) = delete;

  // Layers [k0, k0 + slab.grid().dims.z), right after the previous slab's.
  // Throws std::logic_error out of order.
  void add(std::int64_t k0, const BitVolume& slab);
  // The same layers as runs (a stored result read as its runs): the cost
  // is the runs', not the voxels'.
  void add(std::int64_t k0, const RunSlab& slab);
  // After the last layer. Throws std::logic_error if layers are missing.
  ComponentReport finish();

 private:
  class Phase;
  void check_next(std::int64_t k0) const;
  glm::i64vec3 dims_;
  int threads_;
  std::unique_ptr<Phase> parts_, voids_;
  std::int64_t next_k_ = 0;
};

// Model-space centre of a region's centroid.
glm::dvec3 region_centroid_model(const VoxelRegion& region, const Grid& grid);

}  // namespace voxd
