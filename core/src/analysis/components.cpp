#include "voxd/analysis/components.h"

#include <algorithm>
#include <bit>
#include <numeric>
#include <span>
#include <stdexcept>
#include <string>
#include <tuple>

#include <glm/common.hpp>

#include "analysis/row_runs.h"
#include "voxd/bit_slabs.h"
#include "voxd/parallel.h"

namespace voxd {
namespace {

using Int128 = __int128;

// What a region has gathered so far: exact integer sums.
struct Acc {
  std::uint64_t n = 0;
  Int128 si = 0, sj = 0, sk = 0;
  glm::i64vec3 lo{0}, hi{0};
  void merge(const Acc& o) {
    if (o.n == 0) return;
    if (n == 0) {
      *this = o;
      return;
    }
    n += o.n, si += o.si, sj += o.sj, sk += o.sk;
    lo = glm::min(lo, o.lo);
    hi = glm::max(hi, o.hi);
  }
  // The run [begin, end) of row (j, k).
  void add_run(std::int64_t begin, std::int64_t end, std::int64_t j, std::int64_t k) {
    const std::int64_t count = end - begin;
    Acc a;
    a.n = static_cast<std::uint64_t>(count);
    a.si = Int128{begin + end - 1} * count / 2;  // Σ i over the run
    a.sj = Int128{j} * count;
    a.sk = Int128{k} * count;
    a.lo = {begin, j, k};
    a.hi = {end - 1, j, k};
    merge(a);
  }
  VoxelRegion region() const {
    const double count = static_cast<double>(n);
    return {n, lo, hi, {static_cast<double>(si) / count, static_cast<double>(sj) / count, static_cast<double>(sk) / count}};
  }
};

// One layer's runs of one phase, row by row: bounds b0, e0, b1, e1, ...
struct LayerRuns {
  std::vector<std::size_t> starts;  // row j's bounds are [starts[j], starts[j + 1])
  std::vector<std::uint32_t> bounds;
  std::vector<std::uint32_t> ids;  // each run's region, after the layer is labelled

  std::span<const std::uint32_t> row(std::int64_t j) const {
    return {bounds.data() + starts[static_cast<std::size_t>(j)], bounds.data() + starts[static_cast<std::size_t>(j) + 1]};
  }
  // The first run of row j, counted over the layer.
  std::size_t first_run(std::int64_t j) const { return starts[static_cast<std::size_t>(j)] / 2; }
};

}  // namespace

// The runs of one phase (solid or empty) labelled layer by layer. Only the
// regions that reach the current layer stay in the union-find: after each
// layer those no run of it continues are final and leave as regions, and the
// rest are renumbered, so memory is two layers' runs and the regions found.
// A run is a node of the union-find; its voxels are added to its region's
// sums once the layer's unions are done, so only regions carry sums.
// `corners`: 26-connectivity (runs touching diagonally join) or 6.
class ComponentLabeller::Phase {
 public:
  Phase(const Grid& grid, bool empty_phase, bool corners, bool drop_outside)
      : dims_(grid.dims), empty_phase_(empty_phase), corners_(corners), drop_outside_(drop_outside) {
    parent_.push_back(0);  // node 0: the world around the grid (voids touching it are not enclosed)
    acc_.emplace_back();
  }

  // Layer k, whose filled runs are layer kk of `slab`.
  void add_layer(const RunSlab& slab, std::int64_t kk, std::int64_t k) {
    const std::int64_t nx = dims_.x, ny = dims_.y;
    take_runs(slab, kk);
    const auto carried = static_cast<std::uint32_t>(parent_.size());  // the regions of earlier layers
    const std::size_t runs = cur_.bounds.size() / 2;
    parent_.resize(carried + runs);
    for (std::size_t r = 0; r < runs; ++r) parent_[carried + r] = static_cast<std::uint32_t>(carried + r);
    const std::int64_t reach = corners_ ? 1 : 0;  // how far past its ends a run touches a neighbour row's run
    for (std::int64_t j = 0; j < ny; ++j) {
      const auto row = cur_.row(j);
      const std::uint32_t first = carried + static_cast<std::uint32_t>(cur_.first_run(j));
      if (drop_outside_)
        for (std::size_t r = 0; r < row.size(); r += 2)
          if (row[r] == 0 || row[r + 1] == nx || j == 0 || j == ny - 1 || k == 0 || k == dims_.z - 1)
            unite(first + static_cast<std::uint32_t>(r / 2), 0);
      // Neighbour rows already seen: this layer's j-1, the previous
      // layer's j-1, j, j+1 (j only for 6-connectivity).
      if (j > 0) {
        const std::uint32_t other = carried + static_cast<std::uint32_t>(cur_.first_run(j - 1));
        link_rows(row, first, cur_.row(j - 1), [&](std::size_t q) { return other + static_cast<std::uint32_t>(q); }, reach);
      }
      if (k > 0)
        for (std::int64_t jj = std::max<std::int64_t>(0, j - reach); jj <= std::min(ny - 1, j + reach); ++jj) {
          const std::size_t other = prev_.first_run(jj);
          link_rows(row, first, prev_.row(jj), [&](std::size_t q) { return prev_.ids[other + q]; }, reach);
        }
    }
    // Each run's voxels to its region; the regions this layer continues
    // become the next layer's nodes 1, 2, ... (the outside stays node 0).
    renumbered_.assign(parent_.size(), kNone);
    renumbered_[0] = 0;
    std::vector<Acc> next{acc_[0]};
    cur_.ids.resize(runs);
    for (std::int64_t j = 0; j < ny; ++j) {
      const auto row = cur_.row(j);
      const std::size_t first = cur_.first_run(j);
      for (std::size_t r = 0; r < row.size(); r += 2) {
        const std::uint32_t root = find(carried + static_cast<std::uint32_t>(first + r / 2));
        std::uint32_t& slot = renumbered_[root];
        if (slot == kNone) {
          slot = static_cast<std::uint32_t>(next.size());
          next.push_back(root < carried ? acc_[root] : Acc{});
        }
        next[slot].add_run(row[r], row[r + 1], j, k);
        cur_.ids[first + r / 2] = slot;
      }
    }
    // Regions of earlier layers that no run of this one continues are final.
    for (std::uint32_t id = 1; id < carried; ++id) {
      const std::uint32_t root = find(id);
      if (renumbered_[root] == kNone) {
        regions_.push_back(acc_[root].region());
        renumbered_[root] = kDone;
      }
    }
    acc_ = std::move(next);
    parent_.resize(acc_.size());
    for (std::uint32_t id = 0; id < parent_.size(); ++id) parent_[id] = id;
    std::swap(prev_, cur_);
  }

  std::vector<VoxelRegion> finish() {
    for (std::uint32_t id = 1; id < acc_.size(); ++id) regions_.push_back(acc_[id].region());
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
  static constexpr std::uint32_t kNone = UINT32_MAX, kDone = UINT32_MAX - 1;

  // This phase's runs of layer kk of `slab`: its filled runs, or the gaps
  // between them for the empty phase.
  void take_runs(const RunSlab& slab, std::int64_t kk) {
    const auto nx = static_cast<std::uint32_t>(dims_.x);
    cur_.starts.clear();
    cur_.bounds.clear();
    cur_.starts.push_back(0);
    for (std::int64_t j = 0; j < dims_.y; ++j) {
      const auto filled = slab.row(j, kk);
      if (!empty_phase_) {
        cur_.bounds.insert(cur_.bounds.end(), filled.begin(), filled.end());
      } else {
        std::uint32_t from = 0;
        for (std::size_t r = 0; r < filled.size(); r += 2) {
          if (filled[r] > from) cur_.bounds.insert(cur_.bounds.end(), {from, filled[r]});
          from = filled[r + 1];
        }
        if (from < nx) cur_.bounds.insert(cur_.bounds.end(), {from, nx});
      }
      cur_.starts.push_back(cur_.bounds.size());
    }
  }

  std::uint32_t find(std::uint32_t a) {
    while (parent_[a] != a) a = parent_[a] = parent_[parent_[a]];
    return a;
  }
  // The smaller id stays the root (so the outside, node 0, always does) and
  // takes the other's sums. Only regions of earlier layers have sums while
  // a layer is linked: a region of this layer's runs alone has a larger id
  // than any of them, so it never is the root of one.
  void unite(std::uint32_t a, std::uint32_t b) {
    a = find(a);
    b = find(b);
    if (a == b) return;
    if (a > b) std::swap(a, b);
    parent_[b] = a;
    if (b < acc_.size()) acc_[a].merge(acc_[b]);
  }
  // Unites each run of `row` (nodes first, first + 1, ...) with the runs of
  // `other` it touches: overlapping, or with `reach` 1 also diagonally
  // adjacent. Both rows' runs are sorted and apart, so one merge-like walk
  // finds every touching pair.
  template <class OtherId>
  void link_rows(std::span<const std::uint32_t> row, std::uint32_t first, std::span<const std::uint32_t> other,
                 const OtherId& other_id, std::int64_t reach) {
    std::size_t p = 0, q = 0;
    while (p < row.size() && q < other.size()) {
      const std::int64_t ab = row[p], ae = row[p + 1], bb = other[q], be = other[q + 1];
      if (ab < be + reach && bb < ae + reach) unite(first + static_cast<std::uint32_t>(p / 2), other_id(q / 2));
      if (ae <= be) p += 2;
      if (be <= ae) q += 2;
    }
  }

  glm::i64vec3 dims_;
  bool empty_phase_, corners_, drop_outside_;
  std::vector<std::uint32_t> parent_;
  std::vector<Acc> acc_;  // the sums of the regions carried from earlier layers, by node
  std::vector<std::uint32_t> renumbered_;
  LayerRuns prev_, cur_;
  std::vector<VoxelRegion> regions_;
};

ComponentLabeller::ComponentLabeller(const Grid& grid, int threads)
    : dims_(grid.dims), threads_(threads),
      parts_(std::make_unique<Phase>(grid, /*empty_phase=*/false, /*corners=*/true, /*drop_outside=*/false)),
      voids_(std::make_unique<Phase>(grid, /*empty_phase=*/true, /*corners=*/false, /*drop_outside=*/true)) {}
ComponentLabeller::~ComponentLabeller() = default;

void ComponentLabeller::check_next(std::int64_t k0) const {
  if (k0 != next_k_) throw std::logic_error("ComponentLabeller: slab at layer " + std::to_string(k0) +
                                            " where layer " + std::to_string(next_k_) + " was expected");
}

void ComponentLabeller::add(std::int64_t k0, const RunSlab& slab) {
  check_next(k0);
  // The two phases share nothing: one thread each.
  parallel_for(0, 2, 1, std::min(threads_ > 0 ? threads_ : default_thread_count(), 2), [&](std::int64_t a, std::int64_t b) {
    for (std::int64_t phase = a; phase < b; ++phase)
      for (std::int64_t kk = 0; kk < slab.grid().dims.z; ++kk) (phase == 0 ? parts_ : voids_)->add_layer(slab, kk, k0 + kk);
  });
  next_k_ += slab.grid().dims.z;
}

void ComponentLabeller::add(std::int64_t k0, const BitVolume& slab) {
  check_next(k0);
  // The runs of a batch of layers, found a layer a thread, then labelled.
  const std::int64_t nz = slab.grid().dims.z, nx = slab.grid().dims.x, ny = slab.grid().dims.y;
  const int threads = threads_ > 0 ? threads_ : default_thread_count();
  const std::int64_t batch = std::max<std::int64_t>(16, 4 * threads);
  std::vector<RunSlab> layers(static_cast<std::size_t>(std::min(batch, nz)));
  RunSlab runs;
  for (std::int64_t b0 = 0; b0 < nz; b0 += batch) {
    const std::int64_t n = std::min(batch, nz - b0);
    parallel_for(0, n, 1, threads, [&](std::int64_t a, std::int64_t b) {
      for (std::int64_t l = a; l < b; ++l) {
        RunSlab& layer = layers[static_cast<std::size_t>(l)];
        layer.reset(slab_grid(slab.grid(), b0 + l, 1));
        for (std::int64_t j = 0; j < ny; ++j) {
          detail::for_each_row_run(slab.row(j, b0 + l), slab.row_words(), nx, false, [&](std::int64_t begin, std::int64_t end) {
            layer.add_run(static_cast<std::uint32_t>(begin), static_cast<std::uint32_t>(end));
          });
          layer.end_row();
        }
      }
    });
    runs.reset(slab_grid(slab.grid(), b0, n));
    for (std::int64_t l = 0; l < n; ++l) runs.append_rows(layers[static_cast<std::size_t>(l)]);
    add(k0 + b0, runs);
  }
}

ComponentReport ComponentLabeller::finish() {
  if (next_k_ != dims_.z)
    throw std::logic_error("ComponentLabeller: " + std::to_string(next_k_) + " of " + std::to_string(dims_.z) +
                           " layers were added");
  return {parts_->finish(), voids_->finish()};
}

ComponentReport find_components(const BitVolume& volume, int threads) {
  ComponentLabeller labeller(volume.grid(), threads);
  labeller.add(0, volume);
  return labeller.finish();
}

glm::dvec3 region_centroid_model(const VoxelRegion& region, const Grid& grid) {
  return grid.origin + (region.centroid + glm::dvec3(0.5)) * grid.voxel_size;
}

}  // namespace voxd
