#include "voxd/analysis/components.h"

#include <algorithm>
#include <bit>
#include <numeric>

#include <glm/common.hpp>

namespace voxd {
namespace {

struct Run {
  std::int64_t begin, end;  // [begin, end) along x
};

class UnionFind {
 public:
  std::uint32_t add() {
    parent_.push_back(static_cast<std::uint32_t>(parent_.size()));
    return parent_.back();
  }
  std::uint32_t find(std::uint32_t a) {
    while (parent_[a] != a) a = parent_[a] = parent_[parent_[a]];
    return a;
  }
  void unite(std::uint32_t a, std::uint32_t b) {
    a = find(a);
    b = find(b);
    if (a != b) parent_[std::max(a, b)] = std::min(a, b);
  }
  std::size_t size() const { return parent_.size(); }

 private:
  std::vector<std::uint32_t> parent_;
};

// Runs of set (or, with `invert`, clear) bits of one row of `dims_x` voxels.
void row_runs(const std::uint64_t* row, std::int64_t words, std::int64_t dims_x, bool invert, std::vector<Run>& out) {
  out.clear();
  std::int64_t start = -1;
  for (std::int64_t w = 0; w < words; ++w) {
    std::uint64_t bits = invert ? ~row[w] : row[w];
    if (w == words - 1 && (dims_x & 63)) bits &= (std::uint64_t{1} << (dims_x & 63)) - 1;
    std::int64_t pos = 0;
    while (pos < 64) {
      if (start < 0) {
        const std::uint64_t rest = bits >> pos;
        if (!rest) break;
        pos += std::countr_zero(rest);
        start = w * 64 + pos;
      } else {
        const std::uint64_t rest = ~bits >> pos;
        if (!rest) break;
        pos += std::countr_zero(rest);
        if (pos >= 64) break;
        out.push_back({start, w * 64 + pos});
        start = -1;
      }
    }
  }
  if (start >= 0) out.push_back({start, dims_x});
}

// Labels the runs of one phase (solid or empty) and accumulates regions.
// `corners`: 26-connectivity (runs touching diagonally join) or 6.
std::vector<VoxelRegion> label(const BitVolume& volume, bool empty_phase, bool corners, bool drop_outside) {
  const Grid& g = volume.grid();
  const std::int64_t nx = g.dims.x, ny = g.dims.y, nz = g.dims.z;
  UnionFind uf;
  const std::uint32_t outside = uf.add();  // label 0: the world around the grid
  // Runs and labels of the previous slab (k-1) and of this slab, per row.
  std::vector<std::vector<Run>> prev_runs(static_cast<std::size_t>(ny)), cur_runs(static_cast<std::size_t>(ny));
  std::vector<std::vector<std::uint32_t>> prev_ids(static_cast<std::size_t>(ny)), cur_ids(static_cast<std::size_t>(ny));
  struct Acc {
    std::uint64_t n = 0;
    double si = 0, sj = 0, sk = 0;
    glm::i64vec3 lo{0}, hi{0};
  };
  std::vector<Acc> acc;
  const std::int64_t reach = corners ? 1 : 0;  // how far past its ends a run touches a neighbour row's run
  auto link = [&](const std::vector<Run>& runs, const std::vector<std::uint32_t>& ids, const Run& r, std::uint32_t id) {
    // Runs in a row are sorted; find those overlapping [begin - reach, end + reach).
    auto it = std::lower_bound(runs.begin(), runs.end(), r.begin - reach, [](const Run& a, std::int64_t x) { return a.end <= x; });
    for (; it != runs.end() && it->begin < r.end + reach; ++it) uf.unite(id, ids[static_cast<std::size_t>(it - runs.begin())]);
  };
  for (std::int64_t k = 0; k < nz; ++k) {
    for (std::int64_t j = 0; j < ny; ++j) {
      auto& runs = cur_runs[static_cast<std::size_t>(j)];
      auto& ids = cur_ids[static_cast<std::size_t>(j)];
      row_runs(volume.row(j, k), volume.row_words(), nx, empty_phase, runs);
      ids.resize(runs.size());
      for (std::size_t r = 0; r < runs.size(); ++r) {
        const Run& run = runs[r];
        const std::uint32_t id = uf.add();
        ids[r] = id;
        Acc a;
        a.n = static_cast<std::uint64_t>(run.end - run.begin);
        a.si = static_cast<double>(run.begin + run.end - 1) * 0.5 * static_cast<double>(a.n);
        a.sj = static_cast<double>(j) * static_cast<double>(a.n);
        a.sk = static_cast<double>(k) * static_cast<double>(a.n);
        a.lo = {run.begin, j, k};
        a.hi = {run.end - 1, j, k};
        acc.push_back(a);
        if (drop_outside &&
            (run.begin == 0 || run.end == nx || j == 0 || j == ny - 1 || k == 0 || k == nz - 1))
          uf.unite(id, outside);
        // Neighbour rows already seen: same slab j-1 (and for 26: nothing
        // else in this slab), previous slab j-1, j, j+1.
        if (j > 0) link(cur_runs[static_cast<std::size_t>(j - 1)], cur_ids[static_cast<std::size_t>(j - 1)], run, id);
        if (k > 0) {
          for (std::int64_t dj = corners ? -1 : 0; dj <= (corners ? 1 : 0); ++dj) {
            const std::int64_t jj = j + dj;
            if (jj < 0 || jj >= ny) continue;
            link(prev_runs[static_cast<std::size_t>(jj)], prev_ids[static_cast<std::size_t>(jj)], run, id);
          }
        }
      }
    }
    std::swap(prev_runs, cur_runs);
    std::swap(prev_ids, cur_ids);
  }
  // Gather runs by root.
  std::vector<Acc> by_root(uf.size());
  std::vector<bool> used(uf.size(), false);
  for (std::size_t r = 0; r < acc.size(); ++r) {
    const std::uint32_t root = uf.find(static_cast<std::uint32_t>(r + 1));
    if (drop_outside && root == uf.find(outside)) continue;
    Acc& a = by_root[root];
    const Acc& b = acc[r];
    if (!used[root]) {
      a = b;
      used[root] = true;
      continue;
    }
    a.n += b.n;
    a.si += b.si;
    a.sj += b.sj;
    a.sk += b.sk;
    a.lo = glm::min(a.lo, b.lo);
    a.hi = glm::max(a.hi, b.hi);
  }
  std::vector<VoxelRegion> regions;
  for (std::size_t r = 0; r < by_root.size(); ++r) {
    if (!used[r]) continue;
    const Acc& a = by_root[r];
    const double n = static_cast<double>(a.n);
    regions.push_back({a.n, a.lo, a.hi, {a.si / n, a.sj / n, a.sk / n}});
  }
  // Deterministic: largest first, then by position.
  std::sort(regions.begin(), regions.end(), [](const VoxelRegion& a, const VoxelRegion& b) {
    if (a.voxels != b.voxels) return a.voxels > b.voxels;
    if (a.bbox_min.z != b.bbox_min.z) return a.bbox_min.z < b.bbox_min.z;
    if (a.bbox_min.y != b.bbox_min.y) return a.bbox_min.y < b.bbox_min.y;
    return a.bbox_min.x < b.bbox_min.x;
  });
  return regions;
}

}  // namespace

ComponentReport find_components(const BitVolume& volume) {
  ComponentReport report;
  report.parts = label(volume, /*empty_phase=*/false, /*corners=*/true, /*drop_outside=*/false);
  report.voids = label(volume, /*empty_phase=*/true, /*corners=*/false, /*drop_outside=*/true);
  return report;
}

glm::dvec3 region_centroid_model(const VoxelRegion& region, const Grid& grid) {
  return grid.origin + (region.centroid + glm::dvec3(0.5)) * grid.voxel_size;
}

}  // namespace voxd
