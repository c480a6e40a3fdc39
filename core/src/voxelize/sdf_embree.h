#pragma once
// Exact nearest-triangle queries through Embree's BVH (rtcPointQuery), the
// alternative to the oriented-box tree of sdf_tree.h; SdfTuning picks one.
// Embree culls nodes with float spheres and axis-aligned boxes; the callback
// computes the exact double distance (sdf_triangle.h) and shrinks the query
// radius to it, widened so float culling never drops a nearer triangle.
#include <cstdint>

#include "voxd/mesh.h"
#include "voxelize/sdf_triangle.h"

namespace voxd::sdf {

class EmbreeNearest {
 public:
  static constexpr std::uint32_t kNone = ~std::uint32_t{0};
  struct Hit {
    double d2 = kInfinity;
    std::uint32_t triangle = kNone;  // mesh triangle index; kNone: nothing below the bound
  };

  explicit EmbreeNearest(const Mesh& mesh);
  ~EmbreeNearest();
  EmbreeNearest(const EmbreeNearest&) = delete;
  EmbreeNearest& operator=(const EmbreeNearest&) = delete;

  // Same contract as TriangleTree::nearest.
  Hit nearest(const dvec3& p, double bound2, std::uint32_t hint) const;

 private:
  const Mesh& mesh_;
  void* device_ = nullptr;  // RTCDevice, RTCScene: kept opaque so Embree's header stays here
  void* scene_ = nullptr;
  double slack_ = 0.0;  // absolute widening of the float radius, model units
};

}  // namespace voxd::sdf
