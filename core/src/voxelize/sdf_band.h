#pragma once
// The narrow band of the signed distance field: exact distances wherever
// they are at most the band, by scattering triangles to voxels (see
// voxd/voxelize/sdf.h), and the index arithmetic the rest of the engine shares.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include <glm/vec3.hpp>

#include "analysis/progress_span.h"
#include "voxd/compute_device.h"
#include "voxd/dense_volume.h"
#include "voxd/detail/sdf_gpu.h"
#include "voxd/grid.h"
#include "voxd/mesh.h"

namespace voxd::sdf {

using glm::dvec3;

// The same arithmetic as Grid::center, so values match a brute force over
// grid.center() bit for bit.
inline double centre_coordinate(const Grid& g, int axis, std::int64_t i) {
  return g.origin[axis] + (static_cast<double>(i) + 0.5) * g.voxel_size;
}

// Coordinates in voxel units with voxel i's centre at i, for working out
// which voxels to visit (the distances themselves are computed in model
// units). `first` and `last` give the indices within [x, y] widened by a
// millionth of a voxel (rounding here is under 1e-11 voxel near a grid of
// the sizes allowed), clamped to [0, n - 1]; first > last when empty.
struct IndexSpace {
  dvec3 origin;
  double inv_voxel;

  explicit IndexSpace(const Grid& g) : origin(g.origin), inv_voxel(1.0 / g.voxel_size) {}
  dvec3 operator()(const dvec3& p) const { return (p - origin) * inv_voxel - 0.5; }
  static std::int64_t first(double x, std::int64_t n) {
    return static_cast<std::int64_t>(std::clamp(std::ceil(x - 1e-6), 0.0, static_cast<double>(n)));
  }
  static std::int64_t last(double x, std::int64_t n) {
    return static_cast<std::int64_t>(std::clamp(std::floor(x + 1e-6), -1.0, static_cast<double>(n) - 1.0));
  }
};

struct BandSetup {
  double band = 0.0;       // model units
  double to_model = 1.0;   // output unit -> model units
  double to_output = 1.0;  // model units -> output unit
};

// Neighbouring triangles, scattered together (why: sdf_band.cpp).
constexpr std::uint32_t kClusterSize = 64;

struct Cluster {
  std::uint32_t begin = 0, end = 0;  // ClusterSet::order[begin, end)
  bool flat = false;                 // scattered as a whole; otherwise triangle by triangle
  dvec3 centre{0.0};                 // model units
  dvec3 u{0.0}, w{0.0}, n{0.0};      // orthonormal frame, n the mean normal
  dvec3 half{0.0};                   // half-extents along u, w, n (model units, rounded up)
  double radius = 0.0;               // bounding sphere about the centre
  dvec3 lo{0.0}, hi{0.0};            // bounding box, index space
};

struct ClusterSet {
  std::vector<std::uint32_t> order;  // triangles, cluster by cluster
  std::vector<Cluster> clusters;
};

// Clusters grouped by the chunks of z-slabs their band reaches, so each
// thread owns a chunk of the output.
struct SlabBins {
  std::int64_t slabs_per_chunk = 1;
  std::int64_t chunk_count = 0;
  std::vector<std::uint64_t> offsets;  // chunk c: clusters[offsets[c], offsets[c + 1])
  std::vector<std::uint32_t> clusters;
};

// What the scatter needs before the output exists: the clusters and the
// chunks of z-slabs they reach (made while the output is being filled).
struct BandPlan {
  ClusterSet set;
  SlabBins bins;
};
BandPlan plan_band(const Mesh& mesh, const Grid& g, const BandSetup& s, int threads);

// A thread's scratch for scattering (the probes of a cluster, a row's mask).
struct ProbeBlock;
struct BandScratch {
  BandScratch();
  ~BandScratch();
  BandScratch(BandScratch&&) noexcept;
  BandScratch& operator=(BandScratch&&) noexcept;
  std::unique_ptr<ProbeBlock> probes;
  std::vector<std::uint64_t> mask;
};

// The triangles the scatter goes through (progress's whole).
std::uint64_t band_triangles(const BandPlan& plan);

// Lowers the voxels of one chunk of z-slabs (plan.bins) within the band to
// their exact distance. `values` holds the grid's z layers from `z_origin`
// on (the whole grid, or the chunk's slab alone) and starts at the clamped
// band value. tick(n) reports n more triangles done, every millisecond or so.
void scatter_band_chunk(const Mesh& mesh, const Grid& g, const BandSetup& s, const BandPlan& plan, std::int64_t chunk,
                        DenseVolume<float>& values, std::int64_t z_origin, BandScratch& scratch,
                        const std::function<void(std::uint64_t)>& tick);

// Lowers every voxel within the band of the mesh to its exact distance (in
// the output unit; `values` start at the clamped band value). Threads own
// disjoint z-slabs, so the result does not depend on their number.
void scatter_band(const Mesh& mesh, const Grid& g, const BandSetup& s, const BandPlan& plan, int threads,
                  DenseVolume<float>& values, const detail::ProgressSpan& progress);

// The same band values computed on a device (sdf_gpu.cpp): every voxel of
// `values` written, the unsigned distance in the output unit or `clamped`,
// slab by slab within `gpu_memory` bytes (0: see detail::signed_distance_field_on).
void band_on_device(detail::SdfBackend backend, const Mesh& mesh, const Grid& grid, const BandSetup& s, float clamped,
                    int threads, std::uint64_t gpu_memory, DenseVolume<float>& values,
                    const detail::ProgressSpan& progress, DeviceRunReport* report);
// Bytes of what the device holds of the mesh (detail::sdf_scene_bytes).
std::uint64_t scene_bytes(const Mesh& mesh, const Grid& grid, const BandSetup& s, float clamped);

}  // namespace voxd::sdf
