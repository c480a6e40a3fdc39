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
//
// In parallel, a phase's layers go in runs of layers to phases of their
// own; each but the first starts `open_bottom`: the runs of its first layer
// may join the layer below, which it has not seen. Its regions remember
// which of those runs they hold (a label a run, with a union-find of the
// labels), and a region holding one does not leave as final when it ends
// but waits (`pending_`). The first phase then takes the others over in
// order (absorb): the runs of its last layer and of the next one's first
// are joined as add_layer joins two layers, and only then is a region known
// to be final or to go on. The sums are integers, so the regions are the
// ones a single phase finds, whatever the cut.
class ComponentLabeller::Phase {
 public:
  Phase(const Grid& grid, bool empty_phase, bool corners, bool drop_outside, bool open_bottom = false)
      : dims_(grid.dims), empty_phase_(empty_phase), corners_(corners), drop_outside_(drop_outside),
        open_bottom_(open_bottom) {
    parent_.push_back(0);  // node 0: the world around the grid (voids touching it are not enclosed)
    acc_.emplace_back();
    if (open_bottom_) bottom_.push_back(kNoLabel);
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
      if (has_prev_)
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
    std::vector<std::uint32_t> next_bottom;
    if (open_bottom_) next_bottom.push_back(bottom_[0]);
    // The first layer of a phase open at the bottom: a label a run.
    const bool labelling = open_bottom_ && !has_prev_;
    if (labelling) {
      labels_.resize(runs);
      for (std::uint32_t r = 0; r < runs; ++r) labels_[r] = r;
    }
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
          if (open_bottom_) next_bottom.push_back(root < carried ? bottom_[root] : kNoLabel);
        }
        next[slot].add_run(row[r], row[r + 1], j, k);
        cur_.ids[first + r / 2] = slot;
        if (labelling) join_label(next_bottom[slot], static_cast<std::uint32_t>(first + r / 2));
      }
    }
    // Regions of earlier layers that no run of this one continues are final,
    // or, holding a run of an open bottom, wait for the layer below.
    for (std::uint32_t id = 1; id < carried; ++id) {
      const std::uint32_t root = find(id);
      if (renumbered_[root] == kNone) {
        if (open_bottom_ && bottom_[root] != kNoLabel) {
          pending_.push_back({bottom_[root], acc_[root]});
        } else {
          regions_.push_back(acc_[root].region());
        }
        renumbered_[root] = kDone;
      }
    }
    acc_ = std::move(next);
    bottom_ = std::move(next_bottom);
    parent_.resize(acc_.size());
    for (std::uint32_t id = 0; id < parent_.size(); ++id) parent_[id] = id;
    if (labelling) first_ = cur_;
    std::swap(prev_, cur_);
    has_prev_ = true;
  }

  // Takes over `next`, a phase open at the bottom that labelled the layers
  // right after this one's (this one is not open at the bottom: it began
  // at the grid's first layer, or has taken over all the phases before).
  void absorb(Phase&& next) {
    const std::int64_t ny = dims_.y;
    const auto na = static_cast<std::uint32_t>(acc_.size());
    const auto labels = static_cast<std::uint32_t>(next.labels_.size());
    // Nodes: this phase's regions [0, na), then next's first-layer labels.
    // A group holding any of this phase's regions has one of them as its
    // root, whose sums (merged by unite) are the group's from this side.
    parent_.resize(na + labels);
    for (std::uint32_t id = na; id < na + labels; ++id) parent_[id] = id;
    auto label_node = [&](std::uint32_t label) { return na + next.find_label(label); };
    for (std::uint32_t l = 0; l < labels; ++l) unite(na + l, label_node(l));
    if (next.bottom_[0] != kNoLabel) unite(0, label_node(next.bottom_[0]));  // next's outside is this one's
    const std::int64_t reach = corners_ ? 1 : 0;
    if (has_prev_ && next.has_prev_)
      for (std::int64_t j = 0; j < ny; ++j) {
        const auto row = next.first_.row(j);
        const auto first = na + static_cast<std::uint32_t>(next.first_.first_run(j));
        for (std::int64_t jj = std::max<std::int64_t>(0, j - reach); jj <= std::min(ny - 1, j + reach); ++jj) {
          const std::size_t other = prev_.first_run(jj);
          link_rows(row, first, prev_.row(jj), [&](std::size_t q) { return prev_.ids[other + q]; }, reach);
        }
      }
    // Each group's place: next's outside (slot 0), one of next's regions
    // that reach its last layer, or final. `into` maps next's regions to
    // those they merge into.
    const std::uint32_t outside = find(0);
    std::vector<std::uint32_t> target(parent_.size(), kNone);  // by root: next's slot
    std::vector<std::uint32_t> into(next.acc_.size());
    for (std::uint32_t s = 0; s < into.size(); ++s) into[s] = s;
    for (std::uint32_t s = 1; s < next.acc_.size(); ++s) {
      if (next.bottom_[s] == kNoLabel) continue;
      const std::uint32_t root = find(label_node(next.bottom_[s]));
      std::uint32_t& t = target[root];
      if (root == outside) {
        into[s] = 0;
      } else if (t == kNone) {
        t = s;
        if (root < na) next.acc_[s].merge(acc_[root]);
      } else {
        next.acc_[t].merge(next.acc_[s]);
        into[s] = t;
      }
    }
    // Groups that reach no further than next's regions that ended: final.
    std::vector<std::uint32_t> final_of(parent_.size(), kNone);
    std::vector<Acc> finals;
    auto final_for = [&](std::uint32_t root) -> Acc& {
      std::uint32_t& f = final_of[root];
      if (f == kNone) {
        f = static_cast<std::uint32_t>(finals.size());
        finals.push_back(root < na ? acc_[root] : Acc{});
      }
      return finals[f];
    };
    for (const Pending& p : next.pending_) {
      const std::uint32_t root = find(label_node(p.label));
      if (root == outside) continue;
      if (target[root] != kNone) {
        next.acc_[target[root]].merge(p.acc);
      } else {
        final_for(root).merge(p.acc);
      }
    }
    for (std::uint32_t g = 1; g < na; ++g)
      if (find(g) == g && g != outside && target[g] == kNone) final_for(g);
    for (const Acc& a : finals) regions_.push_back(a.region());
    regions_.insert(regions_.end(), next.regions_.begin(), next.regions_.end());
    // Next's regions, those merged away left out, carry on.
    std::vector<std::uint32_t> renumber(next.acc_.size(), kNone);
    acc_.clear();
    for (std::uint32_t s = 0; s < next.acc_.size(); ++s)
      if (into[s] == s) {
        renumber[s] = static_cast<std::uint32_t>(acc_.size());
        acc_.push_back(next.acc_[s]);
      }
    prev_ = std::move(next.prev_);
    for (std::uint32_t& id : prev_.ids) id = renumber[into[id]];
    parent_.resize(acc_.size());
    for (std::uint32_t id = 0; id < parent_.size(); ++id) parent_[id] = id;
    has_prev_ = has_prev_ || next.has_prev_;
  }

  std::vector<VoxelRegion> finish() {
    for (std::uint32_t id = 1; id < acc_.size(); ++id) regions_.push_back(acc_[id].region());
    parent_.clear();
    acc_.clear();
    // Deterministic: largest first, then by position, then by centroid, so
    // that the order never depends on when each region was found (in
    // parallel, their order in regions_ depends on the cut): regions that
    // tie on every key are the same numbers.
    std::sort(regions_.begin(), regions_.end(), [](const VoxelRegion& a, const VoxelRegion& b) {
      if (a.voxels != b.voxels) return a.voxels > b.voxels;
      const auto key = [](const VoxelRegion& r) {
        return std::tuple(r.bbox_min.z, r.bbox_min.y, r.bbox_min.x, r.bbox_max.z, r.bbox_max.y, r.bbox_max.x,
                          r.centroid.z, r.centroid.y, r.centroid.x);
      };
      return key(a) < key(b);
    });
    return std::move(regions_);
  }

 private:
  static constexpr std::uint32_t kNone = UINT32_MAX, kDone = UINT32_MAX - 1, kNoLabel = UINT32_MAX;

  struct Pending {
    std::uint32_t label;  // a run of the first layer it holds
    Acc acc;
  };

  std::uint32_t find_label(std::uint32_t l) {
    while (labels_[l] != l) l = labels_[l] = labels_[labels_[l]];
    return l;
  }
  // Region `bottom` (a label, or none yet) holds first-layer run `label` too.
  void join_label(std::uint32_t& bottom, std::uint32_t label) {
    if (bottom == kNoLabel) {
      bottom = label;
      return;
    }
    const std::uint32_t a = find_label(bottom), b = find_label(label);
    if (a != b) labels_[std::max(a, b)] = std::min(a, b);
  }

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
    if (b < acc_.size()) {
      acc_[a].merge(acc_[b]);
      if (open_bottom_ && bottom_[b] != kNoLabel) join_label(bottom_[a], bottom_[b]);
    }
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
  bool empty_phase_, corners_, drop_outside_, open_bottom_;
  bool has_prev_ = false;  // a layer was labelled: the next one links to it
  std::vector<std::uint32_t> parent_;
  std::vector<Acc> acc_;  // the sums of the regions carried from earlier layers, by node
  std::vector<std::uint32_t> renumbered_;
  LayerRuns prev_, cur_;
  std::vector<VoxelRegion> regions_;
  // Open at the bottom: the first layer's runs, the union-find of their
  // labels, each carried region's label (or kNoLabel), the regions that
  // ended holding one.
  LayerRuns first_;
  std::vector<std::uint32_t> labels_, bottom_;
  std::vector<Pending> pending_;
};

namespace {

// A run of layers below this is not worth a phase of its own: taking one
// over costs about a layer's runs.
constexpr std::int64_t kMinChunkLayers = 4;

}  // namespace

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
  const int threads = threads_ > 0 ? threads_ : default_thread_count();
  const std::int64_t nz = slab.grid().dims.z;
  // The two phases share nothing: a thread each. With more threads, each
  // phase's layers go in runs of layers to phases of their own (Phase:
  // open at the bottom), which the phase then takes over in order.
  const std::int64_t chunks = std::clamp<std::int64_t>(threads / 2, 1, std::max<std::int64_t>(nz / kMinChunkLayers, 1));
  Grid grid;
  grid.dims = dims_;
  std::vector<std::unique_ptr<Phase>> later(static_cast<std::size_t>(2 * (chunks - 1)));
  for (std::int64_t c = 1; c < chunks; ++c) {
    later[static_cast<std::size_t>(2 * (c - 1))] = std::make_unique<Phase>(grid, false, true, false, /*open_bottom=*/true);
    later[static_cast<std::size_t>(2 * (c - 1) + 1)] = std::make_unique<Phase>(grid, true, false, true, /*open_bottom=*/true);
  }
  auto phase_of = [&](std::int64_t task) -> Phase& {
    const std::int64_t c = task / 2;
    if (c == 0) return task % 2 == 0 ? *parts_ : *voids_;
    return *later[static_cast<std::size_t>(2 * (c - 1) + task % 2)];
  };
  parallel_for(0, 2 * chunks, 1, std::min<std::int64_t>(threads, 2 * chunks), [&](std::int64_t a, std::int64_t b) {
    for (std::int64_t task = a; task < b; ++task) {
      const std::int64_t c = task / 2, from = nz * c / chunks, to = nz * (c + 1) / chunks;
      Phase& phase = phase_of(task);
      for (std::int64_t kk = from; kk < to; ++kk) phase.add_layer(slab, kk, k0 + kk);
    }
  });
  for (std::int64_t task = 2; task < 2 * chunks; ++task) (task % 2 == 0 ? parts_ : voids_)->absorb(std::move(phase_of(task)));
  next_k_ += nz;
}

void ComponentLabeller::add(std::int64_t k0, const BitVolume& slab) {
  check_next(k0);
  // The runs of a batch of layers, found a layer a thread, then labelled:
  // in runs of layers a thread each past two threads, each run of layers
  // long enough (16 layers a thread: 8 to a phase's run) that joining it to
  // the one before (about half a layer's labelling, on one thread) is a
  // small share.
  const std::int64_t nz = slab.grid().dims.z, nx = slab.grid().dims.x, ny = slab.grid().dims.y;
  const int threads = threads_ > 0 ? threads_ : default_thread_count();
  const std::int64_t batch = std::max<std::int64_t>(16, 16 * threads);
  std::vector<RunSlab> layers(static_cast<std::size_t>(std::min(batch, nz)));
  std::vector<const RunSlab*> batch_layers;
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
    // Joined on every thread, as the RLE reader joins its layers.
    runs.reset(slab_grid(slab.grid(), b0, n));
    batch_layers.clear();
    for (std::int64_t l = 0; l < n; ++l) batch_layers.push_back(&layers[static_cast<std::size_t>(l)]);
    runs.append_rows(batch_layers, threads);
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
