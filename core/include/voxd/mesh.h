#pragma once
// Indexed triangle mesh, the engine's input type. Decoders of triangle-soup
// formats (STL) emit three vertices per triangle; weld_vertices() merges them
// when topology is needed (the mesh report, winding numbers). The voxelizers do
// not need welding: they quantize each vertex identically wherever it appears.
#include <array>
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

namespace voxd {

struct Aabb {
  glm::dvec3 min{0.0};
  glm::dvec3 max{0.0};
  glm::dvec3 extent() const { return max - min; }
  glm::dvec3 center() const { return (min + max) * 0.5; }
};

struct Mesh {
  std::vector<glm::vec3> vertices;
  std::vector<std::array<std::uint32_t, 3>> triangles;

  std::size_t triangle_count() const { return triangles.size(); }
  glm::vec3 corner(std::size_t tri, int c) const { return vertices[triangles[tri][c]]; }
};

// Bounding box of the vertices referenced by triangles. Empty mesh -> zero box.
Aabb bounds(const Mesh& mesh);

}  // namespace voxd
