// Signed distance field: the narrow band by scattering triangles to voxels
// (Jones 1996), exact nearest-triangle queries for the rest of the grid when
// asked, the sign from the solid voxelization. See voxd/sdf.h.
#include "voxd/sdf.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <limits>
#include <mutex>
#include <thread>
#include <vector>

#include <glm/geometric.hpp>

#include "analysis/progress_span.h"
#include "voxd/error.h"
#include "voxd/parallel.h"
#include "voxelize/sdf_embree.h"
#include "voxelize/sdf_tree.h"
#include "voxelize/sdf_triangle.h"

namespace voxd {
namespace {

using glm::dvec3;
using sdf::distance2;
using sdf::kInfinity;
using sdf::Triangle;
using sdf::TriangleTree;
inline dvec3 corner(const Mesh& mesh, std::size_t tri, int c) { return dvec3(mesh.corner(tri, c)); }

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

// ---------------------------------------------------------------------------
// Narrow band.

struct BandSetup {
  double band = 0.0;       // model units
  double to_model = 1.0;   // output unit -> model units
  double to_output = 1.0;  // model units -> output unit
};

// Lowers each voxel of slabs [z0, z1) within the band of triangle t to its
// distance if that is smaller. `values` hold float(distance * to_output);
// the minimum of rounded values is the rounded minimum, so the order in which
// triangles arrive does not matter.
//
// Which voxels to visit is worked out per row in index space (voxel i's
// centre at coordinate i), cheap and with a margin for rounding: the band of
// the bounding box, of the bounding sphere and of the plane. Each visited
// voxel then gets two lower bounds in model units, relative to the triangle
// (so small numbers, small rounding): its distance to the plane and to the
// bounding sphere. If either reaches its current value the triangle cannot
// lower it; only then is the exact distance computed. Once the nearer
// triangles have been by, the sphere skips most voxels (the plane alone does
// not: along a curved surface the neighbours' planes pass close to a voxel).
void scatter_triangle(const Triangle& t, const Grid& g, const BandSetup& s, std::int64_t z0, std::int64_t z1,
                      DenseVolume<float>& values) {
  const IndexSpace index_of(g);
  const double band = s.band * index_of.inv_voxel, band2 = band * band;  // voxels
  const dvec3 lo = index_of(glm::min(glm::min(t.a, t.b), t.c)), hi = index_of(glm::max(glm::max(t.a, t.b), t.c));
  const dvec3 centroid = (t.a + t.b + t.c) / 3.0;
  const double radius =
      std::sqrt(std::max({glm::dot(t.a - centroid, t.a - centroid), glm::dot(t.b - centroid, t.b - centroid),
                          glm::dot(t.c - centroid, t.c - centroid)})) * (1.0 + 1e-9);
  const dvec3 centroid_i = index_of(centroid);
  const double reach = band + radius * index_of.inv_voxel, reach2 = reach * reach;
  const dvec3 unit = t.degenerate ? dvec3(0.0) : t.n / std::sqrt(t.nn);
  const dvec3 a_i = index_of(t.a);
  // Restrict rows by the plane only where that is well conditioned.
  const double inv_unit_x = std::abs(unit.x) > 1e-3 ? 1.0 / unit.x : 0.0;

  const std::int64_t k0 = std::max(z0, IndexSpace::first(lo.z - band, g.dims.z));
  const std::int64_t k1 = std::min(z1 - 1, IndexSpace::last(hi.z + band, g.dims.z));
  const std::int64_t j0 = IndexSpace::first(lo.y - band, g.dims.y), j1 = IndexSpace::last(hi.y + band, g.dims.y);
  for (std::int64_t k = k0; k <= k1; ++k) {
    const auto kk = static_cast<double>(k);
    const double dz = std::max({lo.z - kk, kk - hi.z, 0.0}), sz = kk - centroid_i.z;
    const double cz = centre_coordinate(g, 2, k);
    float* slab = values.slab(k);
    for (std::int64_t j = j0; j <= j1; ++j) {
      const auto jj = static_cast<double>(j);
      const double dy = std::max({lo.y - jj, jj - hi.y, 0.0}), sy = jj - centroid_i.y;
      const double box_rest2 = band2 - dy * dy - dz * dz, sphere_rest2 = reach2 - sy * sy - sz * sz;
      if (box_rest2 < 0.0 || sphere_rest2 < 0.0) continue;
      const double bx = std::sqrt(box_rest2), sx = std::sqrt(sphere_rest2);
      double from = std::max(lo.x - bx, centroid_i.x - sx), to = std::min(hi.x + bx, centroid_i.x + sx);
      const double plane_yz_i = unit.y * (jj - a_i.y) + unit.z * (kk - a_i.z);
      if (inv_unit_x != 0.0) {  // |plane_yz_i + unit.x (i - a_i.x)| <= band
        const double p0 = a_i.x + (-band - plane_yz_i) * inv_unit_x, p1 = a_i.x + (band - plane_yz_i) * inv_unit_x;
        from = std::max(from, std::min(p0, p1));
        to = std::min(to, std::max(p0, p1));
      }
      const std::int64_t i0 = IndexSpace::first(from, g.dims.x), i1 = IndexSpace::last(to, g.dims.x);

      const double cy = centre_coordinate(g, 1, j);
      const double plane_yz = unit.y * (cy - t.a.y) + unit.z * (cz - t.a.z);
      const double sphere_yz2 = (cy - centroid.y) * (cy - centroid.y) + (cz - centroid.z) * (cz - centroid.z);
      float* row = slab + j * g.dims.x;
      for (std::int64_t i = i0; i <= i1; ++i) {
        const double cx = centre_coordinate(g, 0, i);
        const double limit = static_cast<double>(row[i]) * s.to_model;
        const double plane = plane_yz + unit.x * (cx - t.a.x);
        if (plane * plane >= limit * limit) continue;
        const double sphere2 = (cx - centroid.x) * (cx - centroid.x) + sphere_yz2;
        if (sphere2 >= (limit + radius) * (limit + radius)) continue;
        const double d2 = distance2(t, dvec3(cx, cy, cz));
        if (d2 >= limit * limit) continue;
        row[i] = std::min(row[i], static_cast<float>(std::sqrt(d2) * s.to_output));
      }
    }
  }
}

// Triangles grouped by the chunks of z-slabs their band reaches, so each
// thread owns a chunk of the output.
struct SlabBins {
  std::int64_t slabs_per_chunk = 1;
  std::int64_t chunk_count = 0;
  std::vector<std::uint64_t> offsets;    // chunk c: triangles[offsets[c], offsets[c + 1])
  std::vector<std::uint32_t> triangles;
};

SlabBins bin_by_slab(const Mesh& mesh, const Grid& g, double band, int threads) {
  SlabBins bins;
  const std::int64_t nz = g.dims.z;
  bins.slabs_per_chunk = std::clamp<std::int64_t>(nz / (8 * threads), 1, 16);
  bins.chunk_count = (nz + bins.slabs_per_chunk - 1) / bins.slabs_per_chunk;
  const std::size_t n = mesh.triangle_count();
  const IndexSpace index_of(g);
  const double band_voxels = band * index_of.inv_voxel;
  std::vector<std::int64_t> first(n), last(n);
  for (std::size_t t = 0; t < n; ++t) {
    // The same slabs as scatter_triangle's, by the same arithmetic.
    const dvec3 a = corner(mesh, t, 0), b = corner(mesh, t, 1), c = corner(mesh, t, 2);
    const std::int64_t k0 = IndexSpace::first(index_of(glm::min(glm::min(a, b), c)).z - band_voxels, nz);
    const std::int64_t k1 = IndexSpace::last(index_of(glm::max(glm::max(a, b), c)).z + band_voxels, nz);
    first[t] = k0 / bins.slabs_per_chunk;
    last[t] = k0 <= k1 ? k1 / bins.slabs_per_chunk : first[t] - 1;
  }
  bins.offsets.assign(static_cast<std::size_t>(bins.chunk_count) + 1, 0);
  for (std::size_t t = 0; t < n; ++t)
    for (std::int64_t c = first[t]; c <= last[t]; ++c) ++bins.offsets[static_cast<std::size_t>(c) + 1];
  for (std::size_t c = 1; c < bins.offsets.size(); ++c) bins.offsets[c] += bins.offsets[c - 1];
  bins.triangles.resize(bins.offsets.back());
  std::vector<std::uint64_t> cursor(bins.offsets.begin(), bins.offsets.end() - 1);
  for (std::size_t t = 0; t < n; ++t)
    for (std::int64_t c = first[t]; c <= last[t]; ++c)
      bins.triangles[cursor[static_cast<std::size_t>(c)]++] = static_cast<std::uint32_t>(t);
  return bins;
}

void scatter_band(const Mesh& mesh, const Grid& g, const BandSetup& s, int threads, DenseVolume<float>& values,
                  const detail::ProgressSpan& progress) {
  const SlabBins bins = bin_by_slab(mesh, g, s.band, threads);
  // Cancellation and progress every this many triangles (~1 ms of work).
  constexpr std::uint64_t kTick = 512;
  const auto total = static_cast<double>(std::max<std::uint64_t>(bins.triangles.size(), 1));
  std::atomic<std::uint64_t> done{0};
  parallel_for(0, bins.chunk_count, 1, threads, [&](std::int64_t c0, std::int64_t c1) {
    for (std::int64_t c = c0; c < c1; ++c) {
      progress.check_cancelled();
      const std::int64_t z0 = c * bins.slabs_per_chunk, z1 = std::min(g.dims.z, z0 + bins.slabs_per_chunk);
      std::uint64_t pending = 0;
      for (std::uint64_t x = bins.offsets[static_cast<std::size_t>(c)]; x < bins.offsets[static_cast<std::size_t>(c) + 1]; ++x) {
        const std::size_t t = bins.triangles[x];
        scatter_triangle(Triangle(corner(mesh, t, 0), corner(mesh, t, 1), corner(mesh, t, 2)), g, s, z0, z1, values);
        if (++pending == kTick) {
          progress.check_cancelled();
          progress.report(static_cast<double>(done.fetch_add(pending) + pending) / total);
          pending = 0;
        }
      }
      progress.report(static_cast<double>(done.fetch_add(pending) + pending) / total);
    }
  });
  progress.report(1.0);
}

template <class Nearest>
void fill_beyond_band(const Nearest& tree, const Grid& g, const BandSetup& s, float clamped, int threads,
                      DenseVolume<float>& values, const detail::ProgressSpan& queries) {
  const std::int64_t nx = g.dims.x, ny = g.dims.y, rows = ny * g.dims.z;
  std::atomic<std::int64_t> done{0};
  parallel_for(0, rows, std::max<std::int64_t>(1, rows / (threads * 64)), threads, [&](std::int64_t r0, std::int64_t r1) {
    for (std::int64_t r = r0; r < r1; ++r) {
      queries.check_cancelled();
      const std::int64_t j = r % ny, k = r / ny;
      float* row = values.slab(k) + j * nx;
      const double cy = centre_coordinate(g, 1, j), cz = centre_coordinate(g, 2, k);
      // The previous voxel's distance bounds this one's (d is 1-Lipschitz),
      // and its nearest triangle is usually this one's too.
      double previous = -1.0;
      std::uint32_t hint = Nearest::kNone;
      for (std::int64_t i = 0; i < nx; ++i) {
        if ((i & 255) == 255) queries.check_cancelled();
        if (row[i] < clamped) {  // exact from the band
          previous = static_cast<double>(row[i]) * s.to_model;
          continue;
        }
        const dvec3 p(centre_coordinate(g, 0, i), cy, cz);
        // The margin covers the float rounding of band values and of the
        // centres' spacing.
        const double bound = previous >= 0.0 ? (previous + g.voxel_size) * (1.0 + 1e-6) : kInfinity;
        typename Nearest::Hit hit = tree.nearest(p, bound * bound, hint);
        if (hit.triangle == Nearest::kNone) hit = tree.nearest(p, kInfinity, Nearest::kNone);
        if (hit.triangle == Nearest::kNone) continue;  // no triangles at all: stays clamped
        previous = std::sqrt(hit.d2);
        hint = hit.triangle;
        row[i] = static_cast<float>(previous * s.to_output);
      }
    }
    queries.report(static_cast<double>(done.fetch_add(r1 - r0) + (r1 - r0)) / static_cast<double>(rows));
  });
  queries.report(1.0);
}

// ---------------------------------------------------------------------------

// The solid voxelization for the sign, on a JobControl of its own: the
// voxelizers report 0..1 on the control they get, and a JobControl's span
// belongs to whoever runs the job, so it cannot be narrowed here. A watcher
// forwards cancellation in and progress (onto `progress`) out.
BitVolume solid_for_sign(const Mesh& mesh, const Grid& grid, const SdfOptions& options,
                         const detail::ProgressSpan& progress) {
  const VoxelizeOptions vo{VoxelMode::solid, options.inside, options.threads};
  if (!progress.control) return voxelize(mesh, grid, vo, nullptr);
  JobControl inner;
  std::mutex mutex;
  std::condition_variable wake;
  bool finished = false;
  std::thread watcher([&] {
    std::unique_lock lock(mutex);
    while (!wake.wait_for(lock, std::chrono::milliseconds(2), [&] { return finished; })) {
      if (progress.control->cancel_requested()) inner.request_cancel();
      progress.report(inner.progress());
    }
  });
  auto stop = [&] {
    {
      std::lock_guard lock(mutex);
      finished = true;
    }
    wake.notify_one();
    watcher.join();
  };
  BitVolume solid;
  try {
    solid = voxelize(mesh, grid, vo, &inner);
  } catch (...) {
    stop();
    throw;
  }
  stop();
  progress.check_cancelled();
  progress.report(1.0);
  return solid;
}

}  // namespace

double point_triangle_distance2(const dvec3& p, const dvec3& a, const dvec3& b, const dvec3& c) {
  return distance2(Triangle(a, b, c), p);
}

DenseVolume<float> signed_distance_field(const Mesh& mesh, const Grid& grid, const SdfOptions& options,
                                         JobControl* control) {
  return signed_distance_field(mesh, grid, options, control, SdfTuning{});
}

DenseVolume<float> signed_distance_field(const Mesh& mesh, const Grid& grid, const SdfOptions& options,
                                         JobControl* control, const SdfTuning& tuning) {
  if (!(options.band > 0.0) || !std::isfinite(options.band))
    throw Error(ErrorCode::invalid_argument, "the distance band must be a positive number of voxels");
  if (!(grid.voxel_size > 0.0) || !std::isfinite(grid.voxel_size))
    throw Error(ErrorCode::invalid_argument, "the voxel size must be a positive number");
  const int threads = options.threads > 0 ? options.threads : default_thread_count();
  const detail::ProgressSpan progress{control, 0.0, 1.0};

  BandSetup s;
  s.band = options.band * grid.voxel_size;
  s.to_model = options.model_units ? 1.0 : grid.voxel_size;
  s.to_output = options.model_units ? 1.0 : 1.0 / grid.voxel_size;
  // Exactly +-band in the output unit, not band * voxel_size / voxel_size.
  const auto clamped = static_cast<float>(options.model_units ? s.band : options.band);

  DenseVolume<float> values(grid, clamped);
  if (grid.voxel_count() == 0) return values;
  const double band_end = options.full ? 0.25 : 1.0;
  const BitVolume solid = solid_for_sign(mesh, grid, options, progress.part(0.0, 0.15));
  scatter_band(mesh, grid, s, threads, values, progress.part(0.15, band_end));
  if (options.full) {
    const detail::ProgressSpan rest = progress.part(band_end, 1.0);
    if (tuning.nearest == SdfTuning::Nearest::embree) {
      const sdf::EmbreeNearest nearest(mesh);
      rest.check_cancelled();
      fill_beyond_band(nearest, grid, s, clamped, threads, values, rest.part(0.1, 1.0));
    } else {
      const TriangleTree tree(mesh, threads, rest.part(0.0, 0.1));
      fill_beyond_band(tree, grid, s, clamped, threads, values, rest.part(0.1, 1.0));
    }
  }

  // Sign; a value of 0 (a centre on the surface) stays +0.
  const bool negate_inside = options.sign == SignConvention::inside_negative;
  const std::int64_t nx = grid.dims.x, ny = grid.dims.y;
  parallel_for(0, grid.dims.z, 1, threads, [&](std::int64_t k0, std::int64_t k1) {
    for (std::int64_t k = k0; k < k1; ++k)
      for (std::int64_t j = 0; j < ny; ++j) {
        float* row = values.slab(k) + j * nx;
        for (std::int64_t i = 0; i < nx; ++i)
          if (row[i] != 0.0f && solid.get(i, j, k) == negate_inside) row[i] = -row[i];
      }
  });
  progress.report(1.0);
  return values;
}

}  // namespace voxd
