#include "voxd/analysis/components.h"

#include <algorithm>
#include <bit>
#include <numeric>
#include <stdexcept>
#include <string>
#include <tuple>

#include <glm/common.hpp>

#include "analysis/row_runs.h"

namespace voxd {
namespace {

struct Run {
  std::int64_t begin, end;  // [begin, end) along x
};

// Runs of set (or, with `invert`, clear) bits of one row of `dims_x` voxels.
void row_runs(const std::uint64_t* row, std::int64_t words, std::int64_t dims_x, bool invert, std::vector<Run>& out) {
  out.clear();
  detail::for_each_row_run(row, words, dims_x, invert, [&](std::int64_t begin, std::int64_t end) { out.push_back({begin, end}); });
}

using Int128 = __int128;

// What a region has gathered so far: exact integer sums.
struct Acc {
  std::uint64_t n = 0;
  Int128 si = 0, sj = 0, sk = 0;
  glm::i64vec3 lo{0}, hi{0};
  void merge(const Acc& o) {
    n += o.n, si += o.si, sj += o.sj, sk += o.sk;
    lo = glm::min(lo, o.lo);
    hi = glm::max(hi, o.hi);
  }
  VoxelRegion region() const {
    const double count = static_cast<double>(n);
    return {n, lo, hi, {static_cast<double>(si) / count, static_cast<double>(sj) / count, static_cast<double>(sk) / count}};
  }
};

}  // namespace

// The runs of one phase (solid or empty) labelled layer by layer. Only the
// regions that reach the current layer stay in the union-find: after each
// layer those no run of it continues are final and leave as regions, and the
// rest are renumbered, so memory is two layers' runs and the regions found.
// `corners`: 26-connectivity (runs touching diagonally join) or 6.
class ComponentLabeller::Phase {
 public:
  Phase(const Grid& grid, bool empty_phase, bool corners, bool drop_outside)
      : dims_(grid.dims), empty_phase_(empty_phase), corners_(corners), drop_outside_(drop_outside),
        prev_runs_(static_cast<std::size_t>(grid.dims.y)), cur_runs_(prev_runs_.size()),
        prev_ids_(prev_runs_.size()), cur_ids_(prev_runs_.size()) {
    add_node({});  // node 0: the world around the grid (voids touching it are not enclosed)
  }

  void add_layer(const BitVolume& slab, std::int64_t kk, std::int64_t k) {
    const std::int64_t nx = dims_.x, ny = dims_.y;
    const std::uint32_t carried = static_cast<std::uint32_t>(parent_.size());  // nodes from earlier layers
    for (std::int64_t j = 0; j < ny; ++j) {
      auto& runs = cur_runs_[static_cast<std::size_t>(j)];
      auto& ids = cur_ids_[static_cast<std::size_t>(j)];
      row_runs(slab.row(j, kk), slab.row_words(), nx, empty_phase_, runs);
      ids.resize(runs.size());
      for (std::size_t r = 0; r < runs.size(); ++r) {
        const Run& run = runs[r];
        const auto n = static_cast<std::uint64_t>(run.end - run.begin);
        Acc a;
        a.n = n;
        a.si = Int128{run.begin + run.end - 1} * static_cast<std::int64_t>(n) / 2;  // Σ i over the run
        a.sj = Int128{j} * static_cast<std::int64_t>(n);
        a.sk = Int128{k} * static_cast<std::int64_t>(n);
        a.lo = {run.begin, j, k};
        a.hi = {run.end - 1, j, k};
        const std::uint32_t id = add_node(a);
        ids[r] = id;
        if (drop_outside_ && (run.begin == 0 || run.end == nx || j == 0 || j == ny - 1 || k == 0 || k == dims_.z - 1))
          unite(id, 0);
        // Neighbour rows already seen: this layer's j-1, the previous
        // layer's j-1, j, j+1 (j only for 6-connectivity).
        if (j > 0) link(cur_runs_[static_cast<std::size_t>(j - 1)], cur_ids_[static_cast<std::size_t>(j - 1)], run, id);
        if (k > 0) {
          for (std::int64_t dj = corners_ ? -1 : 0; dj <= (corners_ ? 1 : 0); ++dj) {
            const std::int64_t jj = j + dj;
            if (jj < 0 || jj >= ny) continue;
            link(prev_runs_[static_cast<std::size_t>(jj)], prev_ids_[static_cast<std::size_t>(jj)], run, id);
          }
        }
      }
    }
    // Regions of earlier layers that no run of this one continues are final.
    std::vector<std::uint32_t> renumbered(parent_.size(), kNone);
    for (auto& ids : cur_ids_)
      for (std::uint32_t& id : ids) id = find(id), renumbered[id] = kLive;
    renumbered[0] = 0;  // the outside stays node 0
    for (std::uint32_t id = 1; id < carried; ++id) {
      const std::uint32_t root = find(id);
      if (renumbered[root] == kNone) {
        regions_.push_back(acc_[root].region());
        renumbered[root] = kDone;
      }
    }
    // The live regions become the next layer's nodes 1, 2, ...
    std::vector<std::uint32_t> parent{0};
    std::vector<Acc> acc{Acc{}};
    for (std::uint32_t id = 1; id < parent_.size(); ++id) {
      if (parent_[id] != id || renumbered[id] != kLive) continue;
      renumbered[id] = static_cast<std::uint32_t>(parent.size());
      parent.push_back(renumbered[id]);
      acc.push_back(acc_[id]);
    }
    for (auto& ids : cur_ids_)
      for (std::uint32_t& id : ids) id = renumbered[id];
    parent_ = std::move(parent);
    acc_ = std::move(acc);
    std::swap(prev_runs_, cur_runs_);
    std::swap(prev_ids_, cur_ids_);
  }

  std::vector<VoxelRegion> finish() {
    for (std::uint32_t id = 1; id < parent_.size(); ++id) regions_.push_back(acc_[id].region());
    parent_.clear();
    acc_.clear();
    // Deterministic: largest first, then by position.
    std::sort(regions_.begin(), regions_.end(), [](const VoxelRegion& a, const VoxelRegion& b) {
      if (a.voxels != b.voxels) return a.voxels > b.voxels;
      const auto key = [](const VoxelRegion& r) {
        return std::tuple(r.bbox_min.z, r.bbox_min.y, r.bbox_min.x, r.bbox_max.z, r.bbox_max.y, r.bbox_max.x);
      };
      return key(a) < key(b);
    });
    return std::move(regions_);
  }

 private:
  static constexpr std::uint32_t kNone = UINT32_MAX, kDone = UINT32_MAX - 1, kLive = UINT32_MAX - 2;

  std::uint32_t add_node(const Acc& a) {
    parent_.push_back(static_cast<std::uint32_t>(parent_.size()));
    acc_.push_back(a);
    return parent_.back();
  }
  std::uint32_t find(std::uint32_t a) {
    while (parent_[a] != a) a = parent_[a] = parent_[parent_[a]];
    return a;
  }
  // The smaller id stays the root (so the outside, node 0, always does) and
  // takes the other's sums.
  void unite(std::uint32_t a, std::uint32_t b) {
    a = find(a);
    b = find(b);
    if (a == b) return;
    if (a > b) std::swap(a, b);
    parent_[b] = a;
    acc_[a].merge(acc_[b]);
  }
  void link(const std::vector<Run>& runs, const std::vector<std::uint32_t>& ids, const Run& r, std::uint32_t id) {
    const std::int64_t reach = corners_ ? 1 : 0;  // how far past its ends a run touches a neighbour row's run
    // Runs in a row are sorted; find those overlapping [begin - reach, end + reach).
    auto it = std::lower_bound(runs.begin(), runs.end(), r.begin - reach, [](const Run& a, std::int64_t x) { return a.end <= x; });
    for (; it != runs.end() && it->begin < r.end + reach; ++it) unite(id, ids[static_cast<std::size_t>(it - runs.begin())]);
  }

  glm::i64vec3 dims_;
  bool empty_phase_, corners_, drop_outside_;
  std::vector<std::uint32_t> parent_;
  std::vector<Acc> acc_;  // a region's sums, at its root
  std::vector<std::vector<Run>> prev_runs_, cur_runs_;
  std::vector<std::vector<std::uint32_t>> prev_ids_, cur_ids_;
  std::vector<VoxelRegion> regions_;
};

ComponentLabeller::ComponentLabeller(const Grid& grid)
    : dims_(grid.dims),
      parts_(std::make_unique<Phase>(grid, /*empty_phase=*/false, /*corners=*/true, /*drop_outside=*/false)),
      voids_(std::make_unique<Phase>(grid, /*empty_phase=*/true, /*corners=*/false, /*drop_outside=*/true)) {}
ComponentLabeller::~ComponentLabeller() = default;

void ComponentLabeller::add(std::int64_t k0, const BitVolume& slab) {
  if (k0 != next_k_) throw std::logic_error("ComponentLabeller: slab at layer " + std::to_string(k0) +
                                            " where layer " + std::to_string(next_k_) + " was expected");
  for (std::int64_t kk = 0; kk < slab.grid().dims.z; ++kk) {
    parts_->add_layer(slab, kk, k0 + kk);
    voids_->add_layer(slab, kk, k0 + kk);
  }
  next_k_ += slab.grid().dims.z;
}

ComponentReport ComponentLabeller::finish() {
  if (next_k_ != dims_.z)
    throw std::logic_error("ComponentLabeller: " + std::to_string(next_k_) + " of " + std::to_string(dims_.z) +
                           " layers were added");
  return {parts_->finish(), voids_->finish()};
}

ComponentReport find_components(const BitVolume& volume) {
  ComponentLabeller labeller(volume.grid());
  labeller.add(0, volume);
  return labeller.finish();
}

glm::dvec3 region_centroid_model(const VoxelRegion& region, const Grid& grid) {
  return grid.origin + (region.centroid + glm::dvec3(0.5)) * grid.voxel_size;
}

}  // namespace voxd
