#include "voxd/grid.h"

#include <cmath>
#include <string>

#include "voxd/error.h"

namespace voxd {
namespace {

void check_dims(const glm::i64vec3& dims) {
  for (int a = 0; a < 3; ++a) {
    if (dims[a] < 1 || dims[a] > kMaxGridDim)
      throw Error(ErrorCode::invalid_argument,
                  "grid dims along " + std::string(1, "xyz"[a]) + " is " + std::to_string(dims[a]) +
                      "; it must be between 1 and " + std::to_string(kMaxGridDim));
  }
}

// Fits a grid of cubic voxels of size h around the bounds, centring the mesh
// in the voxels it needs on each axis, then adds padding on every side.
Grid fit_grid(const Aabb& b, double h, std::int64_t padding, std::int64_t forced_longest, int longest_axis) {
  Grid g;
  g.voxel_size = h;
  const glm::dvec3 ext = b.extent();
  for (int a = 0; a < 3; ++a) {
    // The small tolerance keeps e.g. extent 10 / h 0.1 at 100 voxels rather
    // than 101 because 10/0.1 rounds to 100.00000000000001.
    double n = std::ceil(ext[a] / h * (1.0 - 1e-12));
    if (!(n >= 1.0)) n = 1.0;
    if (n > static_cast<double>(kMaxGridDim))
      throw Error(ErrorCode::invalid_argument,
                  "voxel_size " + std::to_string(h) + " needs more than " + std::to_string(kMaxGridDim) +
                      " voxels along " + std::string(1, "xyz"[a]) + "; use a larger voxel_size");
    auto count = static_cast<std::int64_t>(n);
    if (a == longest_axis && forced_longest > 0) count = forced_longest;
    g.dims[a] = count + 2 * padding;
    g.origin[a] = b.center()[a] - 0.5 * static_cast<double>(count) * h - static_cast<double>(padding) * h;
  }
  check_dims(g.dims);
  return g;
}

}  // namespace

Grid resolve_grid(const GridRequest& request, const Aabb& mesh_bounds) {
  if (request.padding < 0 || request.padding > kMaxGridDim)
    throw Error(ErrorCode::invalid_argument, "padding must be between 0 and " + std::to_string(kMaxGridDim));
  switch (request.kind) {
    case GridRequest::Kind::resolution: {
      if (request.resolution < 1 || request.resolution > kMaxGridDim)
        throw Error(ErrorCode::invalid_argument,
                    "resolution must be between 1 and " + std::to_string(kMaxGridDim));
      const glm::dvec3 ext = mesh_bounds.extent();
      int longest = 0;
      for (int a = 1; a < 3; ++a)
        if (ext[a] > ext[longest]) longest = a;
      if (!(ext[longest] > 0.0) || !std::isfinite(ext[longest]))
        throw Error(ErrorCode::invalid_argument,
                    "the mesh has zero extent, so a resolution cannot set the voxel size; give voxel_size instead");
      const double h = ext[longest] / static_cast<double>(request.resolution);
      return fit_grid(mesh_bounds, h, request.padding, request.resolution, longest);
    }
    case GridRequest::Kind::voxel_size: {
      if (!(request.voxel_size > 0.0) || !std::isfinite(request.voxel_size))
        throw Error(ErrorCode::invalid_argument, "voxel_size must be a positive finite number");
      return fit_grid(mesh_bounds, request.voxel_size, request.padding, 0, -1);
    }
    case GridRequest::Kind::explicit_grid: {
      if (!(request.voxel_size > 0.0) || !std::isfinite(request.voxel_size))
        throw Error(ErrorCode::invalid_argument, "voxel_size must be a positive finite number");
      for (int a = 0; a < 3; ++a)
        if (!std::isfinite(request.origin[a]))
          throw Error(ErrorCode::invalid_argument, "origin must be finite");
      check_dims(request.dims);
      Grid g;
      g.origin = request.origin;
      g.voxel_size = request.voxel_size;
      g.dims = request.dims;
      return g;
    }
  }
  throw Error(ErrorCode::invalid_argument, "unknown grid kind");
}

}  // namespace voxd
