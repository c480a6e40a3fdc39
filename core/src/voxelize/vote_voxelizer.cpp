// Majority vote of ray parity along x, y and z (Nooruddin & Turk 2003, as
// cited by Patil & Ravi): a small crack in the surface corrupts the runs of
// the columns through it along one axis, but rarely along the other two.
#include <algorithm>

#include "voxd/parallel.h"
#include "voxd/voxelize/voxelize.h"
#include "voxelize/parity_voxelizer.h"

namespace voxd {

BitVolume voxelize_vote(const Mesh& mesh, const Grid& grid, int threads, JobControl* control) {
  BitVolume along_x(grid), along_y(grid), along_z(grid);
  detail::ParityVoxelizer(mesh, grid, 0, threads).fill(along_x, control, 0.0, 0.3);
  detail::ParityVoxelizer(mesh, grid, 1, threads).fill(along_y, control, 0.3, 0.6);
  detail::ParityVoxelizer(mesh, grid, 2, threads).fill(along_z, control, 0.6, 0.9);
  const std::size_t slab = along_x.slab_words();
  parallel_for(0, grid.dims.z, 8, threads, [&](std::int64_t k0, std::int64_t k1) {
    std::uint64_t* a = along_x.slab(k0);
    const std::uint64_t* b = along_y.slab(k0);
    const std::uint64_t* c = along_z.slab(k0);
    for (std::size_t w = 0, n = slab * static_cast<std::size_t>(k1 - k0); w < n; ++w)
      a[w] = (a[w] & b[w]) | (a[w] & c[w]) | (b[w] & c[w]);
  });
  if (control) control->set_progress(1.0);
  return along_x;
}

}  // namespace voxd
