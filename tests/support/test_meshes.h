#pragma once
// Meshes with known answers, generated in code (tests and benchmarks).
// All closed meshes are outward oriented (counter-clockwise seen from outside).
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "voxd/bit_volume.h"
#include "voxd/grid.h"
#include "voxd/mesh.h"

namespace voxd::test {

// Axis-aligned box [lo, hi], 12 triangles.
Mesh make_box(glm::dvec3 lo, glm::dvec3 hi);

// A grid of `dims` voxels of `voxel_size` from `origin`; the tests' usual
// one is the unit grid at the model origin, voxel (i, j, k) = [i, i+1) x ...
inline Grid make_grid(glm::i64vec3 dims, glm::dvec3 origin = glm::dvec3(0.0), double voxel_size = 1.0) {
  Grid g;
  g.dims = dims;
  g.origin = origin;
  g.voxel_size = voxel_size;
  return g;
}
inline Grid unit_grid(glm::i64vec3 dims) { return make_grid(dims); }
inline Grid unit_grid(std::int64_t nx, std::int64_t ny, std::int64_t nz, glm::dvec3 origin = glm::dvec3(0.0)) {
  return make_grid({nx, ny, nz}, origin);
}
// A volume of unit voxels each filled with probability `density`, drawn
// from `rng` in memory order (x fastest, then y, then z).
BitVolume random_volume(const glm::i64vec3& dims, double density, std::mt19937& rng);
// `resolution` voxels along the mesh's longest axis, `padding` more around.
// The mesh's parity solid on voxels of `voxel` with 2 empty voxels around.
BitVolume solid_of(const Mesh& mesh, double voxel);

inline Grid grid_for(const Mesh& mesh, std::int64_t resolution, std::int64_t padding) {
  GridRequest r;
  r.resolution = resolution;
  r.padding = padding;
  return resolve_grid(r, bounds(mesh));
}
// Icosahedron subdivided `level` times, projected on a sphere (20 * 4^level triangles).
Mesh make_icosphere(glm::dvec3 center, double radius, int level);
// Torus around z: major radius R, minor radius r, with nu x nv quads.
Mesh make_torus(glm::dvec3 center, double R, double r, int nu, int nv);
// A prism: the simple polygon `outline` (points (x, z), either winding) in
// the x-z plane, extruded along y from y0 to y1. Closed; caps by ear clipping.
Mesh make_extrusion(const std::vector<glm::dvec2>& outline, double y0, double y1);
// A tube around z: outer radius R, inner radius r, from z0 to z1, with
// `segments` facets around (closed, annular caps).
Mesh make_tube(double R, double r, double z0, double z1, int segments);
// Every vertex rotated by `degrees_x` about the x axis, then `degrees_y`
// about the y axis, about the origin.
Mesh rotated(Mesh mesh, double degrees_x, double degrees_y);
// Union of meshes (no welding).
Mesh concat(const std::vector<Mesh>& parts);
// Reverses every triangle (inside-out), e.g. the inner wall of a hollow sphere.
Mesh flipped(Mesh mesh);
// Removes the triangles whose every vertex satisfies coordinate[axis] == value.
Mesh remove_face(Mesh mesh, int axis, double value);
// `mesh` with holes punched in it: every `stride`-th triangle gone (the
// middle one of each run of `stride`), small holes all over its surface.
Mesh punched(const Mesh& mesh, std::size_t stride);
// The triangle soup of `mesh`: three fresh vertices per triangle, as binary STL gives.
Mesh soup_of(const Mesh& mesh);

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
