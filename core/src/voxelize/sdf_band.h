#pragma once
// The narrow band of the signed distance field: exact distances wherever
// they are at most the band, by scattering triangles to voxels (see
// voxd/sdf.h), and the index arithmetic the rest of the engine shares.
#include <algorithm>
#include <cmath>
#include <cstdint>

#include <glm/vec3.hpp>

#include "analysis/progress_span.h"
#include "voxd/dense_volume.h"
#include "voxd/grid.h"
#include "voxd/mesh.h"

namespace voxd::sdf {

using glm::dvec3;

// The same arithmetic as Grid::center, so values match a brute force over
// grid.center() bit for bit.
inline double centre_coordinate(const Grid& g, int axis, std::int64_t i) {
  return g.origin[axis] + (static_cast<double>(i) + 0.5) * g.voxel_size;
}

// Coordinates in voxel units with voxel i's centre at i, for working out
// which voxels to visit (the distances themselves are computed in model
// units). `first` and `last` give the indices within [x, y] widened by a
// millionth of a voxel (rounding here is under 1e-11 voxel near a grid of
// the sizes allowed), clamped to [0, n - 1]; first > last when empty.
struct IndexSpace {
  dvec3 origin;
  double inv_voxel;

  explicit IndexSpace(const Grid& g) : origin(g.origin), inv_voxel(1.0 / g.voxel_size) {}
  dvec3 operator()(const dvec3& p) const { return (p - origin) * inv_voxel - 0.5; }
  static std::int64_t first(double x, std::int64_t n) {
    return static_cast<std::int64_t>(std::clamp(std::ceil(x - 1e-6), 0.0, static_cast<double>(n)));
  }
  static std::int64_t last(double x, std::int64_t n) {
    return static_cast<std::int64_t>(std::clamp(std::floor(x + 1e-6), -1.0, static_cast<double>(n) - 1.0));
  }
};

struct BandSetup {
  double band = 0.0;       // model units
  double to_model = 1.0;   // output unit -> model units
  double to_output = 1.0;  // model units -> output unit
};

// Lowers every voxel within the band of the mesh to its exact distance (in
// the output unit; `values` start at the clamped band value). Threads own
// disjoint z-slabs, so the result does not depend on their number.
void scatter_band(const Mesh& mesh, const Grid& g, const BandSetup& s, int threads, DenseVolume<float>& values,
                  const detail::ProgressSpan& progress);

}  // namespace voxd::sdf
