#include "voxd/analysis/skin_removal.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "voxd/analysis/distance_transform.h"
#include "voxd/error.h"
#include "voxd/parallel.h"

namespace voxd {
namespace {

using Depth = std::uint16_t;
constexpr std::uint32_t kMaxDepth = std::numeric_limits<Depth>::max();

// One axis of the city-block distance: d[i] = min(d[i], d[i-1] + 1) forward
// and min(d[i], d[i+1] + 1) backward, with empty space beyond both ends.
void sweep(Depth* d, std::int64_t n, std::int64_t stride) {
  std::uint32_t prev = 0;
  for (std::int64_t i = 0; i < n; ++i) {
    Depth& v = d[i * stride];
    prev = std::min<std::uint32_t>(v, prev + 1);
    v = static_cast<Depth>(prev);
  }
  std::uint32_t next = 0;
  for (std::int64_t i = n - 1; i >= 0; --i) {
    Depth& v = d[i * stride];
    next = std::min<std::uint32_t>(v, next + 1);
    v = static_cast<Depth>(next);
  }
}

}  // namespace


DenseVolume<Depth> peel_depth(const BitVolume& volume, int threads, PeelMetric metric) {
  const Grid& g = volume.grid();
  if (std::max({g.dims.x, g.dims.y, g.dims.z}) >= static_cast<std::int64_t>(kMaxDepth))
    throw Error(ErrorCode::limit_exceeded, "peel depth supports grids up to 65534 voxels along an axis");
  DenseVolume<Depth> d(g, 0);
  if (metric == PeelMetric::euclidean) {
    // ceil(sqrt(d2)) exactly: the smallest r with r * r >= d2.
    const DenseVolume<std::uint32_t> d2 = squared_distance_transform(volume, threads);
    const auto& src = d2.values();
    auto& dst = d.values();
    for (std::size_t i = 0; i < src.size(); ++i) {
      if (src[i] == 0) continue;
      auto r = static_cast<std::uint64_t>(std::sqrt(static_cast<double>(src[i])));
      while (r * r > src[i]) --r;
      while (r * r < src[i]) ++r;
      dst[i] = static_cast<Depth>(r);
    }
    return d;
  }
  const std::int64_t nx = g.dims.x, ny = g.dims.y, nz = g.dims.z;
  // Start: filled = "infinity" (capped), empty = 0; then sweep x, y, z.
  parallel_for(0, nz, 1, threads, [&](std::int64_t k0, std::int64_t k1) {
    for (std::int64_t k = k0; k < k1; ++k)
      for (std::int64_t j = 0; j < ny; ++j) {
        Depth* line = &d.at(0, j, k);
        const std::uint64_t* row = volume.row(j, k);
        for (std::int64_t i = 0; i < nx; ++i) line[i] = ((row[i >> 6] >> (i & 63)) & 1u) ? static_cast<Depth>(kMaxDepth) : 0;
        sweep(line, nx, 1);
      }
  });
  // y sweeps: per slab, each column i; z sweeps: per row j, each column i.
  parallel_for(0, nz, 1, threads, [&](std::int64_t k0, std::int64_t k1) {
    for (std::int64_t k = k0; k < k1; ++k)
      for (std::int64_t i = 0; i < nx; ++i) sweep(&d.at(i, 0, k), ny, nx);
  });
  parallel_for(0, ny, 1, threads, [&](std::int64_t j0, std::int64_t j1) {
    for (std::int64_t j = j0; j < j1; ++j)
      for (std::int64_t i = 0; i < nx; ++i) sweep(&d.at(i, j, 0), nz, nx * ny);
  });
  return d;
}

PeelSummary summarize_peeling(const DenseVolume<Depth>& depth) {
  PeelSummary s;
  for (Depth v : depth.values()) {
    if (!v) continue;
    if (v > s.voxels_per_layer.size()) s.voxels_per_layer.resize(v, 0);
    ++s.voxels_per_layer[v - 1u];
  }
  s.max_depth = static_cast<std::uint32_t>(s.voxels_per_layer.size());
  if (s.max_depth > 0) s.innermost = find_components(peeled(depth, s.max_depth - 1)).parts;
  return s;
}

BitVolume peeled(const DenseVolume<Depth>& depth, std::uint32_t layers) {
  const Grid& g = depth.grid();
  BitVolume out(g);
  for (std::int64_t k = 0; k < g.dims.z; ++k)
    for (std::int64_t j = 0; j < g.dims.y; ++j) {
      const Depth* line = &depth.at(0, j, k);
      std::uint64_t* row = out.row(j, k);
      for (std::int64_t i = 0; i < g.dims.x; ++i)
        if (line[i] > layers) row[i >> 6] |= std::uint64_t{1} << (i & 63);
    }
  return out;
}

}  // namespace voxd
