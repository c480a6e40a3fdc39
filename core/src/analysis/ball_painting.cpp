// The painting engine of local and wall thickness (analysis/ball_painting.h):
// a dense phase over bit rows while balls paint a good share of what they
// walk, then a sparse phase over the few voxels left.
#include "analysis/ball_painting.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <memory>
#include <vector>

#include "analysis/distance_transform_impl.h"
#include "voxd/parallel.h"
#include "voxd/uncleared_vector.h"

namespace voxd::detail {

std::int64_t isqrt(std::int64_t n) {
  auto r = static_cast<std::int64_t>(std::sqrt(static_cast<double>(n)));
  while (r * r > n) --r;
  while ((r + 1) * (r + 1) <= n) ++r;
  return r;
}

std::int64_t ceil_sqrt(std::int64_t n) {
  const std::int64_t r = isqrt(n);
  return r * r == n ? r : r + 1;
}

namespace {

// See the dense phase's exit test.
constexpr std::int64_t kSparseRowsPerVoxel = 32;

// Dense phase: the voxels still without a value as one bit each (BitVolume
// layout) with a count per (y, z) row, so a ball's rows that hold nothing to
// paint cost one comparison. Threads own disjoint chunks of z-slabs and paint
// every ball's part in their slabs, so no two threads write the same voxel.
class RowPainter {
 public:
  RowPainter(const BitVolume& solid, DenseVolume<float>& out, const BallAccepts& accepts)
      : bits_(solid.clone()), out_(out), accepts_(accepts) {
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
  std::int64_t paint(const Ball& ball, std::int64_t cx, std::int64_t cy, std::int64_t cz, std::int64_t k0,
                     std::int64_t k1, std::int64_t& rows) {
    const std::int64_t r2 = ball.r2;
    const float value = ball.value;
    const std::int64_t rz = isqrt(r2);
    const std::int64_t zlo = std::max(k0, cz - rz), zhi = std::min(k1 - 1, cz + rz);
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
          if (hit != 0 && accepts_) {
            for (std::uint64_t m = hit; m != 0; m &= m - 1) {
              const int b = std::countr_zero(m);
              if (!accepts_(ball, (w << 6) + b, y, z)) hit &= ~(std::uint64_t{1} << b);
            }
          }
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
  const BallAccepts& accepts_;
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

  // Paints every leftover voxel in the ball centred at c that it accepts.
  std::int64_t paint(const Ball& ball, std::int64_t cx, std::int64_t cy, std::int64_t cz, const BallAccepts& accepts,
                     DenseVolume<float>& out) {
    if (nodes_.empty()) return 0;
    return visit(0, ball, cx, cy, cz, accepts, out);
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

  std::int64_t visit(std::uint32_t id, const Ball& ball, std::int64_t cx, std::int64_t cy, std::int64_t cz,
                     const BallAccepts& accepts, DenseVolume<float>& out) {
    const std::int64_t r2 = ball.r2;
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
        if (accepts && !accepts(ball, p.x, p.y, p.z)) continue;
        p.unpainted = 0;
        out.at(p.x, p.y, p.z) = ball.value;
        ++painted;
      }
    } else {
      const std::uint32_t right = n.right;
      painted = visit(id + 1, ball, cx, cy, cz, accepts, out) + visit(right, ball, cx, cy, cz, accepts, out);
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
    // On every thread: a square root a cell, 2 million cells at 512^3, was
    // the largest pass wall thickness left on one thread.
    parallel_for(0, static_cast<std::int64_t>(bound_.size()), std::int64_t{1} << 16, threads,
                 [&](std::int64_t c0, std::int64_t c1) {
                   for (auto i = static_cast<std::size_t>(c0); i < static_cast<std::size_t>(c1); ++i) {
                     const double d = std::sqrt(static_cast<double>(d2.values()[i])) - slack;
                     const double v = d > 0.0 ? static_cast<double>(kCell) * d : 0.0;
                     // floor(v^2) minus one for rounding: still a lower bound on
                     // an integer squared distance.
                     bound_[i] = static_cast<std::uint32_t>(std::max(0.0, std::floor(v * v) - 1.0));
                   }
                 });
  }

  bool may_reach(std::int64_t x, std::int64_t y, std::int64_t z, std::int64_t r2) const {
    const std::size_t c = static_cast<std::size_t>(x / kCell + cx_ * (y / kCell + cy_ * (z / kCell)));
    return bound_[c] <= r2;
  }

 private:
  std::int64_t cx_ = 0, cy_ = 0;
  UnclearedVector<std::uint32_t> bound_;  // written whole, on every thread
};

}  // namespace

std::int64_t paint_balls_largest_first(const BitVolume& solid, DenseVolume<float>& out, const BallSource& balls,
                                       const BallContained& contained, const BallPaintingTuning& tuning, int threads,
                                       const ProgressSpan& progress, const BallAccepts& accepts) {
  const Grid& grid = solid.grid();
  const std::int64_t nx = grid.dims.x, ny = grid.dims.y, nz = grid.dims.z;
  const int nthreads = threads;
  auto coordinates = [&](std::uint64_t v, std::int64_t& x, std::int64_t& y, std::int64_t& z) {
    x = static_cast<std::int64_t>(v % static_cast<std::uint64_t>(nx));
    y = static_cast<std::int64_t>((v / static_cast<std::uint64_t>(nx)) % static_cast<std::uint64_t>(ny));
    z = static_cast<std::int64_t>(v / static_cast<std::uint64_t>(nx * ny));
  };

  RowPainter rows(solid, out, accepts);
  const std::int64_t filled = rows.remaining();
  const auto voxels = static_cast<std::int64_t>(grid.voxel_count());
  // The sparse phase starts once the leftovers fit a small tree: from then on
  // a ball that paints little costs a tree walk instead of all its rows.
  const std::int64_t sparse_at =
      tuning.sparse_from >= 0 ? tuning.sparse_from : std::max<std::int64_t>(1 << 12, voxels / 256);
  auto report = [&](std::int64_t left) {
    progress.report(static_cast<double>(filled - left) / static_cast<double>(std::max<std::int64_t>(filled, 1)));
  };

  // Dense phase, in batches of about a tenth of the voxel count in ball rows.
  const std::int64_t grain = std::max<std::int64_t>(1, nz / (static_cast<std::int64_t>(nthreads) * 4));
  const std::int64_t batch_rows = std::max<std::int64_t>(voxels / 10, 1 << 20);
  std::vector<Ball> batch;
  bool exhausted = false;
  while (rows.remaining() > sparse_at && !exhausted) {
    progress.check_cancelled();
    batch.clear();
    for (std::int64_t budget = 0; budget < batch_rows;) {
      Ball c;
      if (!balls(c)) {
        exhausted = true;
        break;
      }
      std::int64_t x, y, z;
      coordinates(c.index, x, y, z);
      if (contained(x, y, z, c.r2)) continue;
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
        const std::int64_t n = rows.paint(batch[i], x, y, z, k0, k1, visited);
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
  std::int64_t unpainted = rows.remaining();
  if (unpainted > 0 && !exhausted) {
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
      Ball c;
      while (batch.size() < kBatch && (more = balls(c))) {
        std::int64_t x, y, z;
        coordinates(c.index, x, y, z);
        if (reach->may_reach(x, y, z, c.r2) && !contained(x, y, z, c.r2)) batch.push_back(c);
      }
      parallel_for(0, static_cast<std::int64_t>(trees.size()), 1, nthreads, [&](std::int64_t t0, std::int64_t t1) {
        for (std::int64_t t = t0; t < t1; ++t) {
          LeftoverTree& tree = trees[static_cast<std::size_t>(t)];
          for (std::size_t i = 0; i < batch.size() && tree.remaining() > 0; ++i) {
            std::int64_t x, y, z;
            coordinates(batch[i].index, x, y, z);
            tree.paint(batch[i], x, y, z, accepts, out);
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
    unpainted = left;
  }
  progress.report(1.0);
  return unpainted;
}

}  // namespace voxd::detail
