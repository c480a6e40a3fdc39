#include "voxd/mesh.h"

#include <limits>

#include <glm/common.hpp>

namespace voxd {

Aabb bounds(const Mesh& mesh) {
  if (mesh.triangles.empty()) return {};
  constexpr double inf = std::numeric_limits<double>::infinity();
  glm::dvec3 lo(inf), hi(-inf);
  // Only vertices referenced by triangles count: decoders may keep unused ones.
  for (const auto& t : mesh.triangles) {
    for (std::uint32_t v : t) {
      const glm::dvec3 p(mesh.vertices[v]);
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    }
  }
  return {lo, hi};
}

}  // namespace voxd
