#include "voxd/transform.h"

#include <cmath>
#include <limits>

#include <glm/common.hpp>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>

#include "voxd/error.h"

namespace voxd {

glm::dmat3 rotation_from_axis_angle(glm::dvec3 axis, double angle_deg) {
  const double len = glm::length(axis);
  if (!(len > 0.0) || !std::isfinite(len) || !std::isfinite(angle_deg))
    throw Error(ErrorCode::invalid_argument, "rotation axis must be a finite non-zero vector and angle finite");
  const glm::dquat q = glm::angleAxis(glm::radians(angle_deg), axis / len);
  return glm::mat3_cast(q);
}

glm::dmat3 rotation_from_quaternion(double w, double x, double y, double z) {
  const double n = std::sqrt(w * w + x * x + y * y + z * z);
  if (!(n > 0.0) || !std::isfinite(n))
    throw Error(ErrorCode::invalid_argument, "quaternion must be finite and non-zero");
  return glm::mat3_cast(glm::dquat(w / n, x / n, y / n, z / n));
}

glm::dmat3 auto_orient_rotation(const Aabb& bounds) {
  const glm::dvec3 e = bounds.extent();
  int smallest = 0;
  for (int a = 1; a < 3; ++a)
    if (e[a] < e[smallest]) smallest = a;
  // Cyclic permutations are proper rotations (det +1): orientation survives.
  // glm matrices are column-major: m[col][row].
  glm::dmat3 m(0.0);
  for (int a = 0; a < 3; ++a) m[(a + smallest) % 3][a] = 1.0;  // new[a] = old[(a + smallest) % 3]
  return m;
}

void rotate_mesh(Mesh& mesh, const glm::dmat3& rotation) {
  for (auto& v : mesh.vertices) v = glm::vec3(rotation * glm::dvec3(v));
}

Aabb rotated_bounds(const Mesh& mesh, const glm::dmat3& rotation) {
  if (mesh.triangles.empty()) return {};
  Aabb b{glm::dvec3(std::numeric_limits<double>::infinity()), glm::dvec3(-std::numeric_limits<double>::infinity())};
  for (const auto& t : mesh.triangles)
    for (std::uint32_t v : t) {
      const glm::dvec3 p(glm::vec3(rotation * glm::dvec3(mesh.vertices[v])));
      b.min = glm::min(b.min, p);
      b.max = glm::max(b.max, p);
    }
  return b;
}

}  // namespace voxd
