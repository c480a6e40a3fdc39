#pragma once
// Meshes with known answers, generated in code (tests and benchmarks).
// All closed meshes are outward oriented (counter-clockwise seen from outside).
#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "voxd/mesh.h"

namespace voxd::test {

// Axis-aligned box [lo, hi], 12 triangles.
Mesh make_box(glm::dvec3 lo, glm::dvec3 hi);
// Icosahedron subdivided `level` times, projected on a sphere (20 * 4^level triangles).
Mesh make_icosphere(glm::dvec3 center, double radius, int level);
// Torus around z: major radius R, minor radius r, with nu x nv quads.
Mesh make_torus(glm::dvec3 center, double R, double r, int nu, int nv);
// Union of meshes (no welding).
Mesh concat(const std::vector<Mesh>& parts);
// Reverses every triangle (inside-out), e.g. the inner wall of a hollow sphere.
Mesh flipped(Mesh mesh);
// Removes the triangles whose every vertex satisfies coordinate[axis] == value.
Mesh remove_face(Mesh mesh, int axis, double value);

// Exact volume of the icosphere polyhedron (not the sphere), for tight checks.
double mesh_volume(const Mesh& mesh);

// Serializers used to feed decoders.
std::vector<std::uint8_t> to_binary_stl(const Mesh& mesh, const std::string& header = "voxd test");
std::string to_ascii_stl(const Mesh& mesh);
std::string to_obj(const Mesh& mesh);
std::string to_ascii_ply(const Mesh& mesh);
std::vector<std::uint8_t> to_binary_ply(const Mesh& mesh);

// Reads a whole file; empty vector plus a gtest failure-friendly message via
// exception if missing.
std::vector<std::uint8_t> read_file(const std::string& path);
void write_file(const std::string& path, const std::vector<std::uint8_t>& bytes);

}  // namespace voxd::test
