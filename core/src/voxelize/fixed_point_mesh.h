#pragma once
// Mesh vertices in grid-aligned fixed point, the coordinate system in which the
// parity scan conversion is exact.
//
// A coordinate q represents (p - origin) / voxel_size - 1/2 in units of
// 2^-kFixedBits voxel, so voxel centres sit on integer multiples of kFixedOne.
// Quantizing moves a vertex by at most 2^-21 voxel (far below float32 input
// precision at any useful resolution), identically wherever the vertex appears,
// and snaps CAD coordinates that lie on voxel-centre planes up to rounding
// (e.g. 0.35 / 0.1) onto the exact plane, where the tie rule then applies.
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "voxd/grid.h"
#include "voxd/mesh.h"
#include "voxelize/fixed_point.h"

namespace voxd::detail {

using FixedPoint = std::array<std::int64_t, 3>;

// Quantizes corners on the fly: cheaper than a quantized copy of a triangle
// soup (an STL's 3 vertices per triangle), which would cost 24 bytes a vertex
// and a page fault every 170 vertices.
class FixedMesh {
 public:
  FixedMesh(const Mesh& mesh, const Grid& grid);

  const TriangleArray& triangles() const { return mesh_->triangles; }
  // Throws Error(invalid_argument) if the vertex lies absurdly far (2^40
  // voxels) from the grid. Inline: the scan converters call it for every
  // corner of every triangle, and a call costs as much as the arithmetic.
  FixedPoint vertex(std::uint32_t v) const {
    FixedPoint out;
    for (int a = 0; a < 3; ++a) out[a] = coordinate(v, a);
    return out;
  }
  // Where the vertex's float coordinates are, to prefetch them.
  const void* corner_address(std::uint32_t v) const { return &mesh_->vertices[v]; }
  // One coordinate of it (binning needs only the partition axis's).
  std::int64_t coordinate(std::uint32_t v, int axis) const {
    constexpr double half = 0.5 * static_cast<double>(kFixedOne);
    const double q = (static_cast<double>(mesh_->vertices[v][axis]) - origin_[axis]) * scale_ - half;
    if (!(std::fabs(q) < static_cast<double>(kFixedLimit))) [[unlikely]]
      throw_far_vertex();
    return static_cast<std::int64_t>(std::floor(q + 0.5));  // floor inlines, unlike llround
  }

 private:
  [[noreturn]] static void throw_far_vertex();

  const Mesh* mesh_;
  glm::dvec3 origin_;
  double scale_;
};

}  // namespace voxd::detail
