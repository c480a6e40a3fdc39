#pragma once
// The voxel grid: cubic voxels of edge voxel_size, voxel (i,j,k) centred at
// origin + (i+1/2, j+1/2, k+1/2) * voxel_size. `origin` is the minimum corner
// of voxel (0,0,0).
#include <cstdint>
#include <optional>

#include <glm/vec3.hpp>

#include "voxd/mesh.h"

namespace voxd {

struct Grid {
  glm::dvec3 origin{0.0};
  double voxel_size = 1.0;
  glm::i64vec3 dims{0};

  std::uint64_t voxel_count() const {
    return static_cast<std::uint64_t>(dims.x) * static_cast<std::uint64_t>(dims.y) *
           static_cast<std::uint64_t>(dims.z);
  }
  glm::dvec3 center(std::int64_t i, std::int64_t j, std::int64_t k) const {
    return origin + (glm::dvec3(static_cast<double>(i), static_cast<double>(j), static_cast<double>(k)) + 0.5) * voxel_size;
  }
  double voxel_volume() const { return voxel_size * voxel_size * voxel_size; }
};

// How the client asked for the grid. Exactly one of the three forms:
//  - resolution: voxels along the longest bounding-box axis, plus padding;
//  - voxel_size (+ padding): size in model units, dims from the bounding box;
//  - explicit: origin, voxel_size and dims, used as given.
struct GridRequest {
  enum class Kind { resolution, voxel_size, explicit_grid };
  Kind kind = Kind::resolution;
  std::int64_t resolution = 128;
  double voxel_size = 0.0;
  std::int64_t padding = 0;
  glm::dvec3 origin{0.0};
  glm::i64vec3 dims{0};
};

// Largest dims along one axis the engine accepts (keeps index arithmetic and
// fixed-point coordinates far from overflow).
inline constexpr std::int64_t kMaxGridDim = 1 << 16;

// Resolves a request against the mesh bounds. Throws Error(invalid_argument)
// for non-positive sizes, and dims over kMaxGridDim.
Grid resolve_grid(const GridRequest& request, const Aabb& mesh_bounds);

}  // namespace voxd
