#pragma once
// The mesh's own wall thickness by rays, the independent reference for the
// wall-thickness analysis (voxd/analysis/wall_thickness.h, which works on
// voxels): from a point on the surface, along its triangle's inward normal,
// the distance to the first other face the ray meets. This is what Magics
// and Netfabb call ray thickness. Brute force over every triangle in double
// precision, written for the tests: it shares nothing with the analysis.
//
// And how the analysis's map agrees with it: the map read at surface points
// away from sharp edges (where a wall ends, and neither method measures a
// wall), as the error distribution a test asserts on.
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include <glm/vec3.hpp>

#include "voxd/bit_volume.h"
#include "voxd/dense_volume.h"
#include "voxd/mesh.h"

namespace voxd::test {

struct SurfacePoint {
  glm::dvec3 point;
  glm::dvec3 normal;  // outward: its triangle's
  std::uint32_t triangle = 0;
};

// `count` points spread over the surface by area, the same for the same seed.
std::vector<SurfacePoint> sample_surface(const Mesh& mesh, std::size_t count, std::uint64_t seed);

// The ray thickness at `p`: the distance along -normal to the nearest
// triangle other than its own; nullopt when the ray meets none (an open or
// inside-out mesh).
std::optional<double> ray_thickness(const Mesh& mesh, const SurfacePoint& p);
// The same ray's hit: how far, and the outward normal of the face it leaves by.
struct RayHit {
  double distance = 0;
  glm::dvec3 normal{0.0};
};
std::optional<RayHit> ray_hit(const Mesh& mesh, const SurfacePoint& p);

// The edges where the surface turns by more than `degrees` between the two
// triangles that share them (vertices welded by position), as segments.
using Segment = std::pair<glm::dvec3, glm::dvec3>;
std::vector<Segment> sharp_edges(const Mesh& mesh, double degrees);
// The distance from `p` to the nearest of `edges` (infinity for none).
double distance_to_edges(glm::dvec3 p, const std::vector<Segment>& edges);

// The wall-thickness map (voxels) against the ray thickness, at `count`
// points on the faces of walls: at least `edge_margin` voxels from every
// edge sharper than 30°, and no further from one than half their ray (a
// face whose ray runs on past that ends a wall, as a tube's annular cap,
// whose ray is the tube's length; the same at the ray's far end: a bore's
// ray behind a rib runs out along the rib to its rim), and whose ray leaves
// by a face parallel to theirs within 10° (a fillet's ray runs down into
// the junction, across no wall; an oblique ray is longer than the wall by
// 1 / cos of the angle). The map is read at the filled voxel
// under each point (half a voxel inward along its normal, else the nearest
// filled voxel within one voxel).
struct WallAgreement {
  std::size_t points = 0;           // compared
  double within_1 = 0, within_1_5 = 0;  // fractions of points within ±1 and ±1.5 voxels
  double p01 = 0, p50 = 0, p99 = 0;     // percentiles of (map - ray), voxels
  double min = 0, mean = 0;             // of the map at those points, model units
  double ray_min = 0, ray_mean = 0;     // of the ray thickness there, model units
};
WallAgreement compare_with_rays(const Mesh& mesh, const BitVolume& solid, const DenseVolume<float>& map,
                                std::size_t count, double edge_margin = 2.0, std::uint64_t seed = 1);

// Thickness per vertex of a welded mesh (voxels; voxd/analysis/
// surface_thickness.h) against the ray from each vertex along its
// area-weighted normal, at the vertices at least 2 voxels from a sharp edge
// whose ray crosses a wall (the filters of compare_with_rays); every
// vertex, or on a mesh of more than `max_vertices` an even stride of them
// (the rays are brute force).
struct VertexAgreement {
  std::size_t vertices = 0;  // compared
  double within_1 = 0;       // the fraction within ±1 voxel
};
VertexAgreement compare_vertices_with_rays(const Mesh& welded, const std::vector<float>& thickness, double voxel_size,
                                           std::size_t max_vertices = 4000);

}  // namespace voxd::test
