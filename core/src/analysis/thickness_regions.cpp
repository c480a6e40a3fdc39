// Connected thin / thick regions by runs, as parts and voids are found
// (components.cpp): one parallel pass over the map finds each row's runs of
// selected voxels with their sums; a union-find over the runs joins each
// run to the runs it touches (26-connectivity: in the row before in its
// layer, and in the three rows round it in the layer before); each
// region's sums are then gathered from its runs.
//
// Every sum is an integer, the thickness included (in fixed point, exact
// for every value the map can hold from 2^-41 to 2^30 voxels; a larger one,
// infinity too, counts as 2^30), and regions are numbered in the scan order
// of their first voxels, so the regions, their order and
// the probes' answers do not depend on the thread count or on the order in
// which runs are joined. Memory: the runs (28 bytes each; a smooth map has
// a few a row) and a union-find entry each.
#include "voxd/analysis/thickness_regions.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <glm/common.hpp>

#include "analysis/zero_skip.h"
#include "union_find.h"
#include "voxd/parallel.h"

namespace voxd {
namespace {

using Int128 = __int128;

// The fixed point of the thickness sums: 2^-64 voxels.
constexpr int kFixedBits = 64;

// v * 2^64 for a positive float v = m * 2^(e - 150) (e its biased
// exponent, m its 24-bit significand; subnormals have e = 1 and no hidden
// bit): exact from 2^-41 up, the bits below 2^-64 dropped. Values from
// 2^30 voxels up (no grid has such a wall; infinity) count as 2^30, so
// that 2^32 voxels' sum still fits.
Int128 fixed_point(float v) {
  constexpr int kMaxShift = 30 - 24 + kFixedBits;  // m < 2^24: v * 2^64 < 2^(30 + 64)
  const auto bits = std::bit_cast<std::uint32_t>(v);
  const int e = static_cast<int>(bits >> 23);
  const std::uint32_t m = (bits & 0x7fffffu) | (e ? 0x800000u : 0u);
  const int shift = std::max(e, 1) - 150 + kFixedBits;
  if (shift > kMaxShift) return Int128{1} << (30 + kFixedBits);
  return shift >= 0 ? static_cast<Int128>(m) << shift : static_cast<Int128>(m >> std::min(-shift, 31));
}

double from_fixed_point(Int128 sum) { return std::ldexp(static_cast<double>(sum), -kFixedBits); }

// A run of selected voxels [begin, end) of one row, and what it holds.
struct Run {
  std::int32_t begin, end;
};
struct RunSums {
  float extreme;  // the row's min (thin) or max (thick) over the run
  Int128 thickness;
};


// What a region gathers from its runs: integer sums, so any order gives the
// same region.
struct RegionSums {
  std::uint64_t voxels = 0;
  std::int64_t si = 0, sj = 0, sk = 0;
  glm::i64vec3 lo{std::numeric_limits<std::int64_t>::max()}, hi{-1};
  float extreme = 0.0f;
  Int128 thickness = 0;
};

}  // namespace

std::vector<ThicknessRegion> find_thickness_regions(const DenseVolume<float>& thickness, ThicknessRegionKind kind,
                                                    float threshold_voxels, std::uint64_t min_voxels,
                                                    const std::vector<std::size_t>* probes,
                                                    std::vector<std::uint32_t>* probe_regions, int threads) {
  const glm::i64vec3 d = thickness.grid().dims;
  const bool thin = kind == ThicknessRegionKind::thin;
  auto selected = [&](float v) { return v > 0.0f && (thin ? v < threshold_voxels : v > threshold_voxels); };
  if (d.x > std::numeric_limits<std::int32_t>::max())
    throw std::length_error("find_thickness_regions: rows longer than 2^31 voxels");

  // Each row's runs, found layer by layer in parallel; row r = j + ny k.
  const std::int64_t rows = d.y * d.z;
  std::vector<std::vector<Run>> layer_runs(static_cast<std::size_t>(d.z));
  std::vector<std::vector<RunSums>> layer_sums(layer_runs.size());
  std::vector<std::uint32_t> row_count(static_cast<std::size_t>(rows), 0);
  parallel_for(0, d.z, 1, threads, [&](std::int64_t k0, std::int64_t k1) {
    for (std::int64_t k = k0; k < k1; ++k) {
      auto& runs = layer_runs[static_cast<std::size_t>(k)];
      auto& sums = layer_sums[static_cast<std::size_t>(k)];
      for (std::int64_t j = 0; j < d.y; ++j) {
        const float* row = thickness.slab(k) + j * d.x;
        std::uint32_t n = 0;
        for (std::int64_t i = detail::skip_zero_blocks(row, 0, d.x); i < d.x;) {
          if (!selected(row[i])) {
            i = detail::skip_zero_blocks(row, i + 1, d.x);
            continue;
          }
          const std::int64_t begin = i;
          float extreme = row[i];
          Int128 sum = 0;
          for (; i < d.x && selected(row[i]); ++i) {
            extreme = thin ? std::min(extreme, row[i]) : std::max(extreme, row[i]);
            sum += fixed_point(row[i]);
          }
          runs.push_back({static_cast<std::int32_t>(begin), static_cast<std::int32_t>(i)});
          sums.push_back({extreme, sum});
          ++n;
        }
        row_count[static_cast<std::size_t>(j + d.y * k)] = n;
      }
    }
  });
  // The runs numbered in scan order: row r's are [row_start[r], row_start[r + 1]).
  std::vector<std::uint64_t> row_start(static_cast<std::size_t>(rows) + 1, 0);
  for (std::int64_t r = 0; r < rows; ++r)
    row_start[static_cast<std::size_t>(r) + 1] = row_start[static_cast<std::size_t>(r)] + row_count[static_cast<std::size_t>(r)];
  const std::uint64_t total = row_start.back();
  if (total > std::numeric_limits<std::uint32_t>::max())
    throw std::length_error("find_thickness_regions: more than 2^32 runs");
  std::vector<Run> runs;
  std::vector<RunSums> sums;
  runs.reserve(static_cast<std::size_t>(total));
  sums.reserve(static_cast<std::size_t>(total));
  for (std::size_t k = 0; k < layer_runs.size(); ++k) {
    runs.insert(runs.end(), layer_runs[k].begin(), layer_runs[k].end());
    sums.insert(sums.end(), layer_sums[k].begin(), layer_sums[k].end());
    std::vector<Run>().swap(layer_runs[k]);
    std::vector<RunSums>().swap(layer_sums[k]);
  }
  row_count = {};

  // Join each run with the runs it touches in rows already seen: runs of a
  // row are sorted, and touch when they overlap [begin - 1, end + 1).
  detail::UnionFind regions(static_cast<std::size_t>(total));
  auto link = [&](std::uint64_t run, std::int64_t other_row) {
    const Run& r = runs[static_cast<std::size_t>(run)];
    const auto first = runs.begin() + static_cast<std::ptrdiff_t>(row_start[static_cast<std::size_t>(other_row)]);
    const auto last = runs.begin() + static_cast<std::ptrdiff_t>(row_start[static_cast<std::size_t>(other_row) + 1]);
    auto it = std::lower_bound(first, last, r.begin - 1, [](const Run& a, std::int64_t x) { return a.end <= x; });
    for (; it != last && it->begin < r.end + 1; ++it)
      regions.join(static_cast<std::uint32_t>(run), static_cast<std::uint32_t>(it - runs.begin()));
  };
  for (std::int64_t k = 0; k < d.z; ++k)
    for (std::int64_t j = 0; j < d.y; ++j) {
      const std::int64_t row = j + d.y * k;
      for (std::uint64_t run = row_start[static_cast<std::size_t>(row)]; run < row_start[static_cast<std::size_t>(row) + 1]; ++run) {
        if (j > 0) link(run, row - 1);
        if (k > 0)
          for (std::int64_t jj = std::max<std::int64_t>(0, j - 1); jj <= std::min(d.y - 1, j + 1); ++jj) link(run, jj + d.y * (k - 1));
      }
    }

  // Each region's sums, gathered at its root (the run it starts with).
  std::vector<std::uint32_t> region_of(static_cast<std::size_t>(total));
  std::vector<RegionSums> found;  // by first voxel: the order regions are met in scan order
  for (std::int64_t row = 0; row < rows; ++row) {
    const std::int64_t j = row % d.y, k = row / d.y;
    for (std::uint64_t run = row_start[static_cast<std::size_t>(row)]; run < row_start[static_cast<std::size_t>(row) + 1]; ++run) {
      const std::uint32_t root = regions.find(static_cast<std::uint32_t>(run));
      // The root is the region's first run in scan order (the smaller id
      // always stays the root), so its region was numbered when met.
      if (root == run) {
        region_of[static_cast<std::size_t>(run)] = static_cast<std::uint32_t>(found.size());
        found.emplace_back();
      } else {
        region_of[static_cast<std::size_t>(run)] = region_of[root];
      }
      RegionSums& s = found[region_of[static_cast<std::size_t>(run)]];
      const Run& r = runs[static_cast<std::size_t>(run)];
      const RunSums& rs = sums[static_cast<std::size_t>(run)];
      const auto n = static_cast<std::int64_t>(r.end - r.begin);
      s.extreme = s.voxels == 0 ? rs.extreme : thin ? std::min(s.extreme, rs.extreme) : std::max(s.extreme, rs.extreme);
      s.voxels += static_cast<std::uint64_t>(n);
      s.si += (static_cast<std::int64_t>(r.begin) + r.end - 1) * n / 2;
      s.sj += j * n;
      s.sk += k * n;
      s.lo = glm::min(s.lo, glm::i64vec3(r.begin, j, k));
      s.hi = glm::max(s.hi, glm::i64vec3(r.end - 1, j, k));
      s.thickness += rs.thickness;
    }
  }

  // Those of at least min_voxels, most severe first: the thinnest (thickest)
  // extreme, then the larger region, then scan order (found's order).
  std::vector<std::uint32_t> kept;
  for (std::uint32_t f = 0; f < found.size(); ++f)
    if (found[f].voxels >= min_voxels) kept.push_back(f);
  std::stable_sort(kept.begin(), kept.end(), [&](std::uint32_t a, std::uint32_t b) {
    const RegionSums &x = found[a], &y = found[b];
    if (x.extreme != y.extreme) return thin ? x.extreme < y.extreme : x.extreme > y.extreme;
    if (x.voxels != y.voxels) return x.voxels > y.voxels;
    return a < b;
  });
  std::vector<ThicknessRegion> out;
  out.reserve(kept.size());
  std::vector<std::uint32_t> rank(found.size(), 0);  // 1 + place in `out`, 0 for none
  for (const std::uint32_t f : kept) {
    const RegionSums& s = found[f];
    const double count = static_cast<double>(s.voxels);
    ThicknessRegion r;
    r.voxel_count = s.voxels;
    r.bbox_min = s.lo;
    r.bbox_max = s.hi;
    r.centroid = glm::dvec3(static_cast<double>(s.si), static_cast<double>(s.sj), static_cast<double>(s.sk)) / count;
    r.extreme_thickness = s.extreme;
    r.mean_thickness = static_cast<float>(from_fixed_point(s.thickness) / count);
    rank[f] = static_cast<std::uint32_t>(out.size()) + 1;
    out.push_back(r);
  }
  if (probes && probe_regions) {
    probe_regions->assign(probes->size(), 0);
    for (std::size_t p = 0; p < probes->size(); ++p) {
      const std::size_t idx = (*probes)[p];
      if (idx >= thickness.values().size()) continue;
      const auto row = static_cast<std::int64_t>(idx / static_cast<std::size_t>(d.x));
      const auto i = static_cast<std::int32_t>(idx % static_cast<std::size_t>(d.x));
      const auto first = runs.begin() + static_cast<std::ptrdiff_t>(row_start[static_cast<std::size_t>(row)]);
      const auto last = runs.begin() + static_cast<std::ptrdiff_t>(row_start[static_cast<std::size_t>(row) + 1]);
      const auto it = std::upper_bound(first, last, i, [](std::int32_t x, const Run& a) { return x < a.end; });
      if (it != last && it->begin <= i) (*probe_regions)[p] = rank[region_of[static_cast<std::size_t>(it - runs.begin())]];
    }
  }
  return out;
}

}  // namespace voxd
