#include "voxd/analysis/skin_removal.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "analysis/row_runs.h"
#include "voxd/analysis/distance_transform.h"
#include "voxd/error.h"
#include "voxd/parallel.h"

namespace voxd {
namespace {

using Depth = std::uint16_t;
constexpr std::uint32_t kMaxDepth = std::numeric_limits<Depth>::max();

// A row's city-block depths along x, from its runs of filled voxels: voxel
// i of run [b, e) is min(i - b + 1, e - i) steps from the empty voxel (or
// the empty space past the grid) at either end, an empty voxel 0. What a
// sweep forward and back gives, as two ramps a run that the compiler
// vectorizes: the sweeps were a dependent chain a voxel, most of the skin's
// time.
void row_depths(const std::uint64_t* row, std::int64_t words, std::int64_t nx, Depth* line) {
  std::int64_t at = 0;
  detail::for_each_row_run(row, words, nx, false, [&](std::int64_t b, std::int64_t e) {
    std::fill(line + at, line + b, Depth{0});
    const std::int64_t mid = (b + e + 1) / 2;  // the first voxel nearer the run's end
    Depth up = 1;
    for (std::int64_t i = b; i < mid; ++i) line[i] = up++;
    Depth down = static_cast<Depth>(e - mid);
    for (std::int64_t i = mid; i < e; ++i) line[i] = down--;
    at = e;
  });
  std::fill(line + at, line + nx, Depth{0});
}

// Empty space beyond both ends of `width` neighbouring columns of n lines:
// the first and last lines are at most 1 deep.
void clamp_ends(Depth* d, std::int64_t n, std::int64_t stride, std::int64_t width) {
  if (n == 0) return;
  for (Depth* line : {d, d + (n - 1) * stride})
    for (std::int64_t i = 0; i < width; ++i) line[i] = std::min<Depth>(line[i], 1);
}

// The same sweep along y or z (after clamp_ends), for `width` neighbouring columns at once (a
// row's worth, contiguous): line p of the columns starts at d + p * stride.
// Along x every depth is at most half a row, so + 1 cannot wrap.
void sweep_columns(Depth* d, std::int64_t n, std::int64_t stride, std::int64_t width) {
  for (std::int64_t p = 1; p < n; ++p) {
    Depth* cur = d + p * stride;
    const Depth* before = cur - stride;
    for (std::int64_t i = 0; i < width; ++i) cur[i] = std::min<Depth>(cur[i], static_cast<Depth>(before[i] + 1));
  }
  for (std::int64_t p = n - 2; p >= 0; --p) {
    Depth* cur = d + p * stride;
    const Depth* after = cur + stride;
    for (std::int64_t i = 0; i < width; ++i) cur[i] = std::min<Depth>(cur[i], static_cast<Depth>(after[i] + 1));
  }
}

}  // namespace


DenseVolume<Depth> peel_depth(const BitVolume& volume, int threads, PeelMetric metric) {
  const Grid& g = volume.grid();
  if (std::max({g.dims.x, g.dims.y, g.dims.z}) >= static_cast<std::int64_t>(kMaxDepth))
    throw Error(ErrorCode::limit_exceeded, "peel depth supports grids up to 65534 voxels along an axis");
  // The sweeps below write every voxel: their volume starts uninitialized
  // (on a kept block's pages, no page faults); the euclidean depths write
  // only the filled ones.
  DenseVolume<Depth> d = metric == PeelMetric::euclidean ? DenseVolume<Depth>(g, 0)
                                                         : DenseVolume<Depth>(g, DenseVolume<Depth>::Uninitialized{});
  if (metric == PeelMetric::euclidean) {
    // ceil(sqrt(d2)) exactly: the smallest r with r * r >= d2.
    const DenseVolume<std::uint32_t> d2 = squared_distance_transform(volume, threads);
    const auto& src = d2.values();
    auto& dst = d.values();
    const auto n = static_cast<std::int64_t>(src.size());
    parallel_for(0, n, std::max<std::int64_t>(1 << 16, n / 64), threads, [&](std::int64_t a, std::int64_t b) {
      for (auto i = static_cast<std::size_t>(a); i < static_cast<std::size_t>(b); ++i) {
        if (src[i] == 0) continue;
        auto r = static_cast<std::uint64_t>(std::sqrt(static_cast<double>(src[i])));
        while (r * r > src[i]) --r;
        while (r * r < src[i]) ++r;
        dst[i] = static_cast<Depth>(r);
      }
    });
    return d;
  }
  const std::int64_t nx = g.dims.x, ny = g.dims.y, nz = g.dims.z;
  // Depths along x from each row's runs, then swept along y and z. The
  // grid's first and last voxels along y and z have empty space beyond
  // them: clamp_ends.
  parallel_for(0, nz, 1, threads, [&](std::int64_t k0, std::int64_t k1) {
    for (std::int64_t k = k0; k < k1; ++k) {
      for (std::int64_t j = 0; j < ny; ++j) row_depths(volume.row(j, k), volume.row_words(), nx, &d.at(0, j, k));
      clamp_ends(&d.at(0, 0, k), ny, nx, nx);
      sweep_columns(&d.at(0, 0, k), ny, nx, nx);
    }
  });
  // z: a band of rows at a time, every layer.
  const std::int64_t band = std::max<std::int64_t>(1, 4096 / std::max<std::int64_t>(1, nx));
  parallel_for(0, ny, band, threads, [&](std::int64_t j0, std::int64_t j1) {
    Depth* first = &d.at(0, j0, 0);
    const std::int64_t width = (j1 - j0) * nx, stride = nx * ny;
    clamp_ends(first, nz, stride, width);
    sweep_columns(first, nz, stride, width);
  });
  return d;
}

namespace {

// peeled(), reading only the z layers `only` marks (all without it).
BitVolume peeled_in(const DenseVolume<Depth>& depth, std::uint32_t layers, int threads, const std::vector<char>* only) {
  const Grid& g = depth.grid();
  BitVolume out(g);
  parallel_for(0, g.dims.z, 1, threads, [&](std::int64_t k0, std::int64_t k1) {
    for (std::int64_t k = k0; k < k1; ++k) {
      if (only && !(*only)[static_cast<std::size_t>(k)]) continue;
      for (std::int64_t j = 0; j < g.dims.y; ++j) {
        const Depth* line = &depth.at(0, j, k);
        std::uint64_t* row = out.row(j, k);
        for (std::int64_t i = 0; i < g.dims.x; ++i)
          if (line[i] > layers) row[i >> 6] |= std::uint64_t{1} << (i & 63);
      }
    }
  });
  return out;
}

}  // namespace

PeelSummary summarize_peeling(const DenseVolume<Depth>& depth, int threads) {
  // Each layer's counts alone, then added: integers, in any order.
  const std::int64_t nz = depth.grid().dims.z;
  const std::size_t layer = depth.slab_size();
  std::vector<std::vector<std::uint64_t>> counts(static_cast<std::size_t>(nz));
  parallel_for(0, nz, 1, threads, [&](std::int64_t k0, std::int64_t k1) {
    std::vector<std::uint64_t> lanes;
    for (std::int64_t k = k0; k < k1; ++k) {
      // The layer's deepest voxel first (a reduction the compiler
      // vectorizes), then a histogram without a bounds test: blocks of 16
      // empty voxels (most of a layer, often) skipped by one test, the
      // others counted in four interleaved copies, so that runs of equal
      // depths do not wait on one counter's last increment.
      const Depth* v = depth.slab(k);
      Depth top = 0;
      for (std::size_t i = 0; i < layer; ++i) top = std::max(top, v[i]);
      if (top == 0) continue;
      lanes.assign(4 * (static_cast<std::size_t>(top) + 1), 0);
      std::size_t i = 0;
      for (; i + 16 <= layer; i += 16) {
        Depth any = 0;
        for (std::size_t t = 0; t < 16; ++t) any |= v[i + t];
        if (any == 0) continue;
        for (std::size_t t = 0; t < 16; ++t) ++lanes[4 * std::size_t{v[i + t]} + (t & 3)];
      }
      for (; i < layer; ++i) ++lanes[4 * std::size_t{v[i]}];
      auto& c = counts[static_cast<std::size_t>(k)];
      c.resize(top);  // depth d counted at c[d - 1]; empty voxels (0) not at all
      for (std::size_t d = 1; d <= top; ++d) c[d - 1] = lanes[4 * d] + lanes[4 * d + 1] + lanes[4 * d + 2] + lanes[4 * d + 3];
    }
  });
  PeelSummary s;
  for (const auto& c : counts) {
    if (c.size() > s.voxels_per_layer.size()) s.voxels_per_layer.resize(c.size(), 0);
    for (std::size_t d = 0; d < c.size(); ++d) s.voxels_per_layer[d] += c[d];
  }
  s.max_depth = static_cast<std::uint32_t>(s.voxels_per_layer.size());
  if (s.max_depth > 0) {
    // The innermost voxels lie only in the z layers as deep as the deepest
    // (a layer's counts end at its deepest voxel): the others are left out
    // of the scan, not of the result.
    std::vector<char> deepest(static_cast<std::size_t>(nz), 0);
    for (std::int64_t k = 0; k < nz; ++k) deepest[static_cast<std::size_t>(k)] = counts[static_cast<std::size_t>(k)].size() == s.max_depth;
    s.innermost = find_components(peeled_in(depth, s.max_depth - 1, threads, &deepest), threads).parts;
  }
  return s;
}

BitVolume peeled(const DenseVolume<Depth>& depth, std::uint32_t layers, int threads) {
  return peeled_in(depth, layers, threads, nullptr);
}

}  // namespace voxd
