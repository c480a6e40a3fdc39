// Local thickness: every filled voxel is a ball centre; balls are painted
// largest first and each voxel keeps the value of the first ball that covers
// it, which is the largest. See voxd/analysis/local_thickness.h for why this is exact
// and fast.
#include "voxd/analysis/local_thickness.h"
#include "voxd/detail/local_thickness_tuning.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdio>
#include <memory>
#include <mutex>

#include "analysis/distance_transform_impl.h"
#include "voxd/error.h"
#include "voxd/parallel.h"

namespace voxd {
namespace {

// floor(sqrt(n)), exact for every n < 2^52 (the double estimate is corrected).
inline std::int64_t isqrt(std::int64_t n) {
  auto r = static_cast<std::int64_t>(std::sqrt(static_cast<double>(n)));
  while (r * r > n) --r;
  while ((r + 1) * (r + 1) <= n) ++r;
  return r;
}

// See the dense phase's exit test.
constexpr std::int64_t kSparseRowsPerVoxel = 32;

inline float thickness_of(std::int64_t r2) { return static_cast<float>(2.0 * std::sqrt(static_cast<double>(r2))); }

std::int64_t ceil_sqrt(std::int64_t n) {
  const std::int64_t r = isqrt(n);
  return r * r == n ? r : r + 1;
}

// Whether the ball at (x, y, z) with squared radius r2 lies inside the ball of
// one of its 26 neighbours. The ball at c + e (squared radius R') contains it
// when sqrt(R') >= sqrt(r2) + |e|, i.e. R' >= r2 + |e|^2 + 2 sqrt(r2 |e|^2)
// (the continuous containment, sufficient for the lattice balls). Such a ball
// is larger, so it was painted earlier and already covered every voxel of
// this one: skipping it is exact. On walls along the grid axes this drops
// nearly every ball but the mid-plane's; on tilted walls few, as the radius
// seldom grows by a whole step per neighbour.
bool inside_a_neighbour(const DenseVolume<std::uint32_t>& edt, std::int64_t x, std::int64_t y, std::int64_t z,
                        std::int64_t r2) {
  const glm::i64vec3 d = edt.grid().dims;
  std::int64_t need[4] = {0, 0, 0, 0};
  for (std::int64_t e2 = 1; e2 <= 3; ++e2) need[e2] = r2 + e2 + ceil_sqrt(4 * r2 * e2);
  for (int dz = -1; dz <= 1; ++dz) {
    const std::int64_t k = z + dz;
    if (k < 0 || k >= d.z) continue;
    for (int dy = -1; dy <= 1; ++dy) {
      const std::int64_t j = y + dy;
      if (j < 0 || j >= d.y) continue;
      const std::uint32_t* row = edt.slab(k) + j * d.x;
      for (int dx = -1; dx <= 1; ++dx) {
        const std::int64_t i = x + dx;
        const int e2 = dx * dx + dy * dy + dz * dz;
        if (e2 == 0 || i < 0 || i >= d.x) continue;
        if (row[i] >= need[e2]) return true;
      }
    }
  }
  return false;
}

// Every filled voxel is a ball centre, handed out largest squared radius
// first. Most of the time only the largest few percent are ever needed (the
// painting stops when no voxel is left), so the centres are not sorted all at
// once: a histogram of the distance values picks a range of radii holding
// about `want` centres, one parallel scan gathers them, a counting sort
// orders them, and the next range is gathered (twice as large) only when the
// painting asks for more. Within one radius the centres stay in memory order.
struct Centre {
  std::uint64_t index;  // linear voxel index
  std::uint32_t r2;     // squared radius: the distance value there
};

class CentreQueue {
 public:
  CentreQueue(const DenseVolume<std::uint32_t>& edt, int threads, std::uint64_t first_range)
      : edt_(edt), threads_(threads) {
    const auto& d2 = edt.values();
    std::uint32_t max_d2 = 0;
    for (std::uint32_t v : d2) max_d2 = std::max(max_d2, v);
    histogram_.assign(static_cast<std::size_t>(max_d2) + 1, 0);
    for_chunks([&](std::size_t begin, std::size_t end, std::size_t) {
      std::vector<std::uint64_t> h(histogram_.size(), 0);
      for (std::size_t i = begin; i < end; ++i) ++h[d2[i]];
      std::lock_guard lock(mutex_);
      for (std::size_t l = 0; l < h.size(); ++l) histogram_[l] += h[l];
    });
    next_level_ = static_cast<std::int64_t>(max_d2);
    want_ = first_range > 0 ? first_range : std::max<std::uint64_t>(1 << 20, d2.size() / 64);
  }

  // The next centre, or false when every centre has been handed out.
  bool pop(Centre& c) {
    if (pos_ == range_.size() && !refill()) return false;
    c = range_[pos_++];
    return true;
  }

 private:
  template <typename Body>
  void for_chunks(Body&& body) {
    const std::size_t n = edt_.values().size();
    const std::size_t chunk = std::max<std::size_t>(1 << 16, n / (static_cast<std::size_t>(threads_) * 4) + 1);
    const auto chunks = static_cast<std::int64_t>((n + chunk - 1) / chunk);
    parallel_for(0, chunks, 1, threads_, [&](std::int64_t c0, std::int64_t c1) {
      for (std::int64_t c = c0; c < c1; ++c) {
        const std::size_t b = static_cast<std::size_t>(c) * chunk;
        body(b, std::min(n, b + chunk), static_cast<std::size_t>(c));
      }
    });
  }

  bool refill() {
    range_.clear();
    pos_ = 0;
    if (next_level_ < 1) return false;
    // Levels [lo, hi] holding about want_ centres (at least one level).
    const std::int64_t hi = next_level_;
    std::int64_t lo = hi;
    std::uint64_t count = histogram_[static_cast<std::size_t>(hi)];
    while (lo > 1 && count + histogram_[static_cast<std::size_t>(lo - 1)] <= want_) count += histogram_[static_cast<std::size_t>(--lo)];
    next_level_ = lo - 1;
    want_ *= 2;
    if (count == 0) return refill();
    // Gather per chunk (chunk order = memory order), then a stable counting
    // sort by level, descending.
    const auto& d2 = edt_.values();
    const std::size_t n = d2.size();
    const std::size_t chunk = std::max<std::size_t>(1 << 16, n / (static_cast<std::size_t>(threads_) * 4) + 1);
    std::vector<std::vector<Centre>> parts((n + chunk - 1) / chunk);
    const auto ulo = static_cast<std::uint32_t>(lo), uhi = static_cast<std::uint32_t>(hi);
    for_chunks([&](std::size_t begin, std::size_t end, std::size_t c) {
      for (std::size_t i = begin; i < end; ++i)
        if (d2[i] >= ulo && d2[i] <= uhi) parts[c].push_back({i, d2[i]});
    });
    std::vector<std::uint64_t> offset(static_cast<std::size_t>(hi - lo) + 2, 0);
    for (std::int64_t l = hi; l >= lo; --l) {
      offset[static_cast<std::size_t>(hi - l) + 1] = offset[static_cast<std::size_t>(hi - l)] + histogram_[static_cast<std::size_t>(l)];
    }
    range_.resize(count);
    for (const auto& part : parts)
      for (const Centre& c : part) range_[offset[hi - c.r2]++] = c;
    return true;
  }

  const DenseVolume<std::uint32_t>& edt_;
  int threads_;
  std::mutex mutex_;
  std::vector<std::uint64_t> histogram_;
  std::int64_t next_level_ = 0;  // highest level not handed out yet
  std::uint64_t want_ = 0;
  std::vector<Centre> range_;
  std::size_t pos_ = 0;
};

// Dense phase: the voxels still without a value as one bit each (BitVolume
// layout) with a count per (y, z) row, so a ball's rows that hold nothing to
// paint cost one comparison. Threads own disjoint chunks of z-slabs and paint
// every ball's part in their slabs, so no two threads write the same voxel.
class RowPainter {
 public:
  RowPainter(const BitVolume& solid, DenseVolume<float>& out) : bits_(solid.clone()), out_(out) {
    const Grid& g = solid.grid();
    nx_ = g.dims.x;
    ny_ = g.dims.y;
    row_count_.assign(static_cast<std::size_t>(ny_ * g.dims.z), 0);
    for (std::int64_t k = 0; k < g.dims.z; ++k)
      for (std::int64_t j = 0; j < ny_; ++j) {
        const std::uint64_t* row = bits_.row(j, k);
        std::uint32_t n = 0;
        for (std::int64_t w = 0; w < bits_.row_words(); ++w) n += static_cast<std::uint32_t>(std::popcount(row[w]));
        row_count_[static_cast<std::size_t>(j + ny_ * k)] = n;
        remaining_ += n;
      }
  }

  std::int64_t remaining() const { return remaining_; }
  std::int64_t remaining_in(std::int64_t k0, std::int64_t k1) const {
    std::int64_t n = 0;
    for (std::size_t i = static_cast<std::size_t>(k0 * ny_); i < static_cast<std::size_t>(k1 * ny_); ++i) n += row_count_[i];
    return n;
  }
  void painted(std::int64_t n) { remaining_ -= n; }
  const BitVolume& bits() const { return bits_; }

  // Paints the ball (c, r2) within slabs [k0, k1); returns the voxels painted
  // and adds the rows looked at to `rows`.
  std::int64_t paint(std::int64_t cx, std::int64_t cy, std::int64_t cz, std::int64_t r2, std::int64_t k0,
                     std::int64_t k1, std::int64_t& rows) {
    const std::int64_t rz = isqrt(r2);
    const std::int64_t zlo = std::max(k0, cz - rz), zhi = std::min(k1 - 1, cz + rz);
    const float value = thickness_of(r2);
    std::int64_t painted = 0;
    for (std::int64_t z = zlo; z <= zhi; ++z) {
      const std::int64_t rz2 = r2 - (z - cz) * (z - cz);
      const std::int64_t ry = isqrt(rz2);
      const std::int64_t ylo = std::max<std::int64_t>(0, cy - ry), yhi = std::min<std::int64_t>(ny_ - 1, cy + ry);
      std::uint32_t* counts = row_count_.data() + ny_ * z;
      float* out_slab = out_.slab(z);
      rows += yhi - ylo + 1;
      for (std::int64_t y = ylo; y <= yhi; ++y) {
        if (counts[y] == 0) continue;
        const std::int64_t rx = isqrt(rz2 - (y - cy) * (y - cy));
        const std::int64_t xlo = std::max<std::int64_t>(0, cx - rx), xhi = std::min<std::int64_t>(nx_ - 1, cx + rx);
        std::uint64_t* bits = bits_.row(y, z);
        float* row = out_slab + y * nx_;
        for (std::int64_t w = xlo >> 6; w <= xhi >> 6; ++w) {
          std::uint64_t mask = ~std::uint64_t{0};
          if (w == xlo >> 6) mask &= ~std::uint64_t{0} << (xlo & 63);
          if (w == xhi >> 6 && (xhi & 63) != 63) mask &= (std::uint64_t{1} << ((xhi & 63) + 1)) - 1;
          std::uint64_t hit = bits[w] & mask;
          if (hit == 0) continue;
          bits[w] &= ~hit;
          const auto n = static_cast<std::uint32_t>(std::popcount(hit));
          counts[y] -= n;
          painted += n;
          for (; hit != 0; hit &= hit - 1) row[(w << 6) + std::countr_zero(hit)] = value;
        }
      }
    }
    return painted;
  }

 private:
  BitVolume bits_;
  DenseVolume<float>& out_;
  std::int64_t nx_ = 0, ny_ = 0;
  std::vector<std::uint32_t> row_count_;
  std::int64_t remaining_ = 0;
};

// Sparse phase: once few voxels are left (thin tips, sharp edges, the lattice
// fringe of round walls), a ball is tested against those voxels instead of
// walking its rows. A kd-tree over the leftover voxels answers "which of you
// lie in this ball" touching only the subtrees whose box the ball reaches;
// painted voxels leave their subtree's count, and empty subtrees are skipped.
class LeftoverTree {
 public:
  struct Point {
    std::int32_t x, y, z;
    std::uint32_t unpainted;  // 1 until painted
  };

  explicit LeftoverTree(std::vector<Point> points) : points_(std::move(points)) {
    if (!points_.empty()) build(0, static_cast<std::uint32_t>(points_.size()));
  }

  std::int64_t remaining() const { return nodes_.empty() ? 0 : nodes_[0].count; }
  const std::vector<Point>& points() const { return points_; }

  // Paints every leftover voxel in the ball (c, r2) with `value`.
  std::int64_t paint(std::int64_t cx, std::int64_t cy, std::int64_t cz, std::int64_t r2, float value,
                     DenseVolume<float>& out) {
    if (nodes_.empty()) return 0;
    return visit(0, cx, cy, cz, r2, value, out);
  }

 private:
  struct Node {
    std::int32_t lo[3], hi[3];
    std::uint32_t begin, end;
    std::uint32_t right;  // left child is the next node; 0 for a leaf
    std::uint32_t count;  // unpainted points below
  };
  static constexpr std::uint32_t kLeaf = 16;

  std::uint32_t build(std::uint32_t begin, std::uint32_t end) {
    const auto id = static_cast<std::uint32_t>(nodes_.size());
    nodes_.push_back({});
    Node n{};
    n.begin = begin;
    n.end = end;
    n.count = end - begin;
    for (int a = 0; a < 3; ++a) {
      n.lo[a] = INT32_MAX;
      n.hi[a] = INT32_MIN;
    }
    for (std::uint32_t i = begin; i < end; ++i) {
      const std::int32_t c[3] = {points_[i].x, points_[i].y, points_[i].z};
      for (int a = 0; a < 3; ++a) {
        n.lo[a] = std::min(n.lo[a], c[a]);
        n.hi[a] = std::max(n.hi[a], c[a]);
      }
    }
    if (end - begin > kLeaf) {
      int axis = 0;
      for (int a = 1; a < 3; ++a)
        if (n.hi[a] - n.lo[a] > n.hi[axis] - n.lo[axis]) axis = a;
      const std::uint32_t mid = begin + (end - begin) / 2;
      std::nth_element(points_.begin() + begin, points_.begin() + mid, points_.begin() + end,
                       [axis](const Point& p, const Point& q) {
                         return axis == 0 ? p.x < q.x : axis == 1 ? p.y < q.y : p.z < q.z;
                       });
      build(begin, mid);
      n.right = build(mid, end);
    }
    nodes_[id] = n;
    return id;
  }

  std::int64_t visit(std::uint32_t id, std::int64_t cx, std::int64_t cy, std::int64_t cz, std::int64_t r2, float value,
                     DenseVolume<float>& out) {
    Node& n = nodes_[id];
    if (n.count == 0) return 0;
    auto gap = [](std::int64_t c, std::int64_t lo, std::int64_t hi) { return c < lo ? lo - c : c > hi ? c - hi : 0; };
    const std::int64_t gx = gap(cx, n.lo[0], n.hi[0]), gy = gap(cy, n.lo[1], n.hi[1]), gz = gap(cz, n.lo[2], n.hi[2]);
    if (gx * gx + gy * gy + gz * gz > r2) return 0;
    std::int64_t painted = 0;
    if (n.right == 0) {
      for (std::uint32_t i = n.begin; i < n.end; ++i) {
        Point& p = points_[i];
        if (p.unpainted == 0) continue;
        const std::int64_t dx = p.x - cx, dy = p.y - cy, dz = p.z - cz;
        if (dx * dx + dy * dy + dz * dz > r2) continue;
        p.unpainted = 0;
        out.at(p.x, p.y, p.z) = value;
        ++painted;
      }
    } else {
      const std::uint32_t right = n.right;
      painted = visit(id + 1, cx, cy, cz, r2, value, out) + visit(right, cx, cy, cz, r2, value, out);
    }
    nodes_[id].count -= static_cast<std::uint32_t>(painted);
    return painted;
  }

  std::vector<Point> points_;
  std::vector<Node> nodes_;
};

// A lower bound, per cell of kCell^3 voxels, on the squared distance from any
// voxel of the cell to the nearest leftover voxel: from the distance
// transform of the cell grid with cells holding leftovers as the "empty"
// set. Cells d apart (in cells, Euclidean) hold voxels at least
// kCell * (d - sqrt(3)) apart (each axis loses at most one cell), so a ball
// centred in a cell whose bound exceeds its squared radius reaches no
// leftover voxel and is skipped with one lookup.
class LeftoverReach {
 public:
  static constexpr std::int64_t kCell = 4;

  LeftoverReach(const Grid& grid, const std::vector<LeftoverTree>& trees, int threads) {
    Grid cells;
    for (int a = 0; a < 3; ++a) cells.dims[a] = (grid.dims[a] + kCell - 1) / kCell;
    cx_ = cells.dims.x;
    cy_ = cells.dims.y;
    BitVolume clear(cells);  // cells with no leftover voxel
    const std::int64_t words = clear.row_words();
    const std::uint64_t tail = (cx_ & 63) == 0 ? ~std::uint64_t{0} : (std::uint64_t{1} << (cx_ & 63)) - 1;
    for (std::int64_t k = 0; k < cells.dims.z; ++k)
      for (std::int64_t j = 0; j < cy_; ++j) {
        std::uint64_t* row = clear.row(j, k);
        std::fill(row, row + words, ~std::uint64_t{0});
        row[words - 1] = tail;
      }
    for (const LeftoverTree& tree : trees)
      for (const auto& p : tree.points())
        if (p.unpainted != 0) clear.set(p.x / kCell, p.y / kCell, p.z / kCell, false);
    const DenseVolume<std::uint32_t> d2 = detail::squared_distance_transform(clear, threads, detail::ProgressSpan{});
    bound_.resize(d2.values().size());
    const double slack = std::sqrt(3.0);
    for (std::size_t i = 0; i < bound_.size(); ++i) {
      const double d = std::sqrt(static_cast<double>(d2.values()[i])) - slack;
      const double v = d > 0.0 ? static_cast<double>(kCell) * d : 0.0;
      // floor(v^2) minus one for rounding: still a lower bound on an integer
      // squared distance.
      bound_[i] = static_cast<std::uint32_t>(std::max(0.0, std::floor(v * v) - 1.0));
    }
  }

  bool may_reach(std::int64_t x, std::int64_t y, std::int64_t z, std::int64_t r2) const {
    const std::size_t c = static_cast<std::size_t>(x / kCell + cx_ * (y / kCell + cy_ * (z / kCell)));
    return bound_[c] <= r2;
  }

 private:
  std::int64_t cx_ = 0, cy_ = 0;
  std::vector<std::uint32_t> bound_;
};

}  // namespace

DenseVolume<float> local_thickness(const BitVolume& solid, int threads, JobControl* control) {
  return local_thickness(solid, threads, control, detail::LocalThicknessTuning{});
}

DenseVolume<float> local_thickness(const BitVolume& solid, int threads, JobControl* control,
                                   const detail::LocalThicknessTuning& tuning) {
  const Grid& grid = solid.grid();
  const std::int64_t nx = grid.dims.x, ny = grid.dims.y, nz = grid.dims.z;
  const int nthreads = threads > 0 ? threads : default_thread_count();
  const detail::ProgressSpan progress{control, 0.0, 1.0};

  DenseVolume<float> out(grid, 0.0f);
  if (grid.voxel_count() == 0) return out;
  const DenseVolume<std::uint32_t> edt = detail::squared_distance_transform(solid, nthreads, progress.part(0.0, 0.3));
  progress.check_cancelled();
  CentreQueue centres(edt, nthreads, tuning.first_range);
  auto coordinates = [&](std::uint64_t v, std::int64_t& x, std::int64_t& y, std::int64_t& z) {
    x = static_cast<std::int64_t>(v % static_cast<std::uint64_t>(nx));
    y = static_cast<std::int64_t>((v / static_cast<std::uint64_t>(nx)) % static_cast<std::uint64_t>(ny));
    z = static_cast<std::int64_t>(v / static_cast<std::uint64_t>(nx * ny));
  };

  RowPainter rows(solid, out);
  const std::int64_t filled = rows.remaining();
  const auto voxels = static_cast<std::int64_t>(grid.voxel_count());
  // The sparse phase starts once the leftovers fit a small tree: from then on
  // a ball that paints little costs a tree walk instead of all its rows.
  const std::int64_t sparse_at =
      tuning.sparse_from >= 0 ? tuning.sparse_from : std::max<std::int64_t>(1 << 12, voxels / 256);
  auto report = [&](std::int64_t left) {
    progress.report(0.3 + 0.7 * static_cast<double>(filled - left) / static_cast<double>(std::max<std::int64_t>(filled, 1)));
  };

  // Dense phase, in batches of about a tenth of the voxel count in ball rows.
  const std::int64_t grain = std::max<std::int64_t>(1, nz / (static_cast<std::int64_t>(nthreads) * 4));
  const std::int64_t batch_rows = std::max<std::int64_t>(voxels / 10, 1 << 20);
  std::vector<Centre> batch;
  bool exhausted = false;
  while (rows.remaining() > sparse_at && !exhausted) {
    progress.check_cancelled();
    batch.clear();
    for (std::int64_t budget = 0; budget < batch_rows;) {
      Centre c;
      if (!centres.pop(c)) {
        exhausted = true;
        break;
      }
      std::int64_t x, y, z;
      coordinates(c.index, x, y, z);
      if (inside_a_neighbour(edt, x, y, z, c.r2)) continue;
      batch.push_back(c);
      const std::int64_t span = 2 * isqrt(c.r2) + 1;
      budget += span * span;
    }
    std::atomic<std::int64_t> painted_now{0}, rows_now{0};
    parallel_for(0, nz, grain, nthreads, [&](std::int64_t k0, std::int64_t k1) {
      std::int64_t left = rows.remaining_in(k0, k1);
      std::int64_t painted = 0, visited = 0;
      for (std::size_t i = 0; i < batch.size() && left > 0; ++i) {
        std::int64_t x, y, z;
        coordinates(batch[i].index, x, y, z);
        const std::int64_t n = rows.paint(x, y, z, batch[i].r2, k0, k1, visited);
        painted += n;
        left -= n;
        if ((i & 1023) == 0) progress.check_cancelled();
      }
      painted_now += painted;
      rows_now += visited;
    });
    rows.painted(painted_now.load());
    // Rows are the cheap way while a ball paints a good share of what it
    // walks; once a batch paints under one voxel per kSparseRowsPerVoxel rows
    // and the leftovers fit the tree's budget, the tree is cheaper.
    if (tuning.sparse_from < 0 && painted_now.load() * kSparseRowsPerVoxel < rows_now.load() &&
        rows.remaining() <= voxels / 4) {
      break;
    }
    report(rows.remaining());
  }

  // Sparse phase: the leftovers of each z-chunk go into that chunk's tree,
  // and the remaining centres are taken in batches: the reach bound (over
  // all leftovers) drops the balls that cannot reach one, then every chunk
  // walks its own tree with the batch, in parallel, writing only its own
  // slabs. The bound is rebuilt when the leftovers have halved and enough
  // balls went to the trees to pay for it.
  if (rows.remaining() > 0 && !exhausted) {
    const BitVolume& bits = rows.bits();
    std::vector<LeftoverTree> trees;
    for (std::int64_t k0 = 0; k0 < nz; k0 += grain) {
      std::vector<LeftoverTree::Point> points;
      for (std::int64_t k = k0; k < std::min(nz, k0 + grain); ++k)
        for (std::int64_t j = 0; j < ny; ++j) {
          const std::uint64_t* row = bits.row(j, k);
          for (std::int64_t w = 0; w < bits.row_words(); ++w)
            for (std::uint64_t m = row[w]; m != 0; m &= m - 1) {
              const std::int64_t i = (w << 6) + std::countr_zero(m);
              points.push_back({static_cast<std::int32_t>(i), static_cast<std::int32_t>(j), static_cast<std::int32_t>(k), 1});
            }
        }
      trees.emplace_back(std::move(points));
    }
    auto leftovers = [&] {
      std::int64_t n = 0;
      for (const LeftoverTree& t : trees) n += t.remaining();
      return n;
    };
    std::int64_t left = leftovers();
    std::int64_t built_at = left, walks = 0;
    auto reach = std::make_unique<LeftoverReach>(grid, trees, nthreads);
    constexpr std::size_t kBatch = 4096;
    bool more = true;
    while (left > 0 && more) {
      progress.check_cancelled();
      batch.clear();
      Centre c;
      while (batch.size() < kBatch && (more = centres.pop(c))) {
        std::int64_t x, y, z;
        coordinates(c.index, x, y, z);
        if (reach->may_reach(x, y, z, c.r2) && !inside_a_neighbour(edt, x, y, z, c.r2)) batch.push_back(c);
      }
      parallel_for(0, static_cast<std::int64_t>(trees.size()), 1, nthreads, [&](std::int64_t t0, std::int64_t t1) {
        for (std::int64_t t = t0; t < t1; ++t) {
          LeftoverTree& tree = trees[static_cast<std::size_t>(t)];
          for (std::size_t i = 0; i < batch.size() && tree.remaining() > 0; ++i) {
            std::int64_t x, y, z;
            coordinates(batch[i].index, x, y, z);
            tree.paint(x, y, z, batch[i].r2, thickness_of(batch[i].r2), out);
          }
        }
      });
      walks += static_cast<std::int64_t>(batch.size());
      left = leftovers();
      report(left);
      if (left > 0 && left * 2 <= built_at && walks >= tuning.reach_rebuild_queries) {
        built_at = left;
        walks = 0;
        reach = std::make_unique<LeftoverReach>(grid, trees, nthreads);
      }
    }
  }
  progress.report(1.0);
  return out;
}

ThicknessStatistics thickness_statistics(const DenseVolume<float>& thickness, int bins) {
  if (bins < 1) throw Error(ErrorCode::invalid_argument, "thickness histogram needs at least 1 bin");
  ThicknessStatistics st;
  double sum = 0.0;
  for (float v : thickness.values()) {
    if (v <= 0.0f) continue;
    if (st.voxel_count == 0) st.min = st.max = v;
    st.min = std::min<double>(st.min, v);
    st.max = std::max<double>(st.max, v);
    sum += v;
    ++st.voxel_count;
  }
  if (st.voxel_count == 0) return st;
  st.mean = sum / static_cast<double>(st.voxel_count);
  // Second pass for the variance: sum of squared deviations does not lose
  // precision the way sum(v^2) - n mean^2 does.
  st.histogram.assign(static_cast<std::size_t>(bins), 0);
  const double range = st.max - st.min;
  double ss = 0.0;
  for (float v : thickness.values()) {
    if (v <= 0.0f) continue;
    ss += (v - st.mean) * (v - st.mean);
    std::int64_t b = range > 0.0 ? static_cast<std::int64_t>((v - st.min) / range * bins) : 0;
    b = std::clamp<std::int64_t>(b, 0, bins - 1);
    ++st.histogram[static_cast<std::size_t>(b)];
  }
  st.std_dev = std::sqrt(ss / static_cast<double>(st.voxel_count));
  return st;
}

ThicknessErrorBound thickness_error_bound() { return {}; }

std::string thickness_error_statement(double voxel_size) {
  const ThicknessErrorBound b = thickness_error_bound();
  char text[512];
  std::snprintf(text, sizeof text,
                "-%g to +%g voxels (-%g to +%g model units) against the mesh's wall thickness, away from convex "
                "edges and corners (where the largest ball containing a point is smaller by definition): the "
                "voxelization places each face anywhere within a voxel, and a wall N voxels thick reports N (even N) "
                "or N + 1 (odd N)",
                b.below_voxels, b.above_voxels, b.below_voxels * voxel_size, b.above_voxels * voxel_size);
  return text;
}

}  // namespace voxd
