// Exact squared Euclidean distance transform, three separable 1D passes.
//
// Pass x reads the bit rows directly: the 1D distance inside a run of filled
// voxels [a, b) is min(i - a + 1, b - i), because the voxels at a - 1 and b
// are empty (or outside the grid, which counts as empty). Passes y and z take
// the lower envelope of the parabolas (p - q)^2 + g(p) along their axis
// (Meijster et al. 2000, phase 2), in integers with floor division, so the
// result is exact.
//
// Two facts keep the y and z passes cheap and exact:
//  - Treating the outside as empty equals padding the grid with one empty
//    layer: clamping any outside point to that layer keeps it outside and
//    does not move it farther away. So each line gets a zero at -1 and n.
//  - Within a line, a zero (empty voxel) hides everything beyond it: for q
//    between zeros at a and b, any site p outside [a, b] is farther than a
//    or b. So each run of non-zeros is solved on its own, bounded by its two
//    zeros, and empty stretches cost nothing.
//
// Cache: the y and z passes gather kBlock x-adjacent lines at once (one
// 64-byte cache line per step along the strided axis), solve them in a
// contiguous buffer and scatter them back, instead of walking one voxel per
// cache line.
#include "voxd/analysis/distance_transform.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <vector>

#include "analysis/distance_transform_impl.h"
#include "analysis/lower_envelope.h"
#include "voxd/parallel.h"

namespace voxd {
namespace detail {
namespace {

constexpr std::int64_t kBlock = 16;  // uint32 lines gathered together: one cache line

// Solves one padded line in place: line[0] and line[n + 1] are 0 (the outside),
// line[1..n] the values of the previous pass. Each run of non-zeros is solved
// between its bounding zeros.
struct LineSolver {
  std::vector<std::uint32_t> dt;
  std::vector<int> s, t;
  explicit LineSolver(std::int64_t n) : dt(n + 2), s(n + 2), t(n + 2) {}

  void solve(std::uint32_t* line, std::int64_t n) {
    std::int64_t i = 1;
    while (i <= n) {
      if (line[i] == 0) {
        ++i;
        continue;
      }
      const std::int64_t a = i;  // run [a, b)
      while (line[i] != 0) ++i;  // line[n + 1] == 0 stops it
      const std::int64_t b = i;
      const int m = static_cast<int>(b - a + 2);
      const std::uint32_t* g = line + a - 1;
      lower_envelope<false>(g, m, s.data(), t.data(), 0, [&](int u, int site) {
        const std::int64_t d = u - site;
        dt[static_cast<std::size_t>(u)] = static_cast<std::uint32_t>(d * d + static_cast<std::int64_t>(g[site]));
      });
      std::copy(dt.begin() + 1, dt.begin() + m - 1, line + a);
    }
  }
};

// Calls run(a, b) for each maximal run [a, b) of set bits in a row.
template <typename F>
void for_each_run(const std::uint64_t* row, std::int64_t words, std::int64_t nx, F&& run) {
  bool inside = false;
  std::int64_t start = 0;
  for (std::int64_t w = 0; w < words; ++w) {
    const std::uint64_t x = row[w];
    if (!inside && x == 0) continue;
    if (inside && x == ~std::uint64_t{0}) continue;
    int p = 0;
    for (;;) {
      const std::uint64_t y = (inside ? ~x : x) & (~std::uint64_t{0} << p);
      if (y == 0) break;
      const int b = std::countr_zero(y);
      if (inside) {
        run(start, w * 64 + b);
      } else {
        start = w * 64 + b;
      }
      inside = !inside;
      p = b;
    }
  }
  if (inside) run(start, nx);
}

}  // namespace

DenseVolume<std::uint32_t> squared_distance_transform(const BitVolume& solid, int threads,
                                                      const ProgressSpan& progress) {
  const Grid& grid = solid.grid();
  const std::int64_t nx = grid.dims.x, ny = grid.dims.y, nz = grid.dims.z;
  DenseVolume<std::uint32_t> out(grid, 0u);
  if (grid.voxel_count() == 0) return out;
  const int nthreads = threads > 0 ? threads : default_thread_count();
  std::uint32_t* data = out.values().data();
  const std::size_t slab = out.slab_size();

  // Progress: the three passes count as equal thirds.
  std::atomic<std::int64_t> done{0};
  auto tick = [&](std::int64_t items, std::int64_t total, int pass) {
    const std::int64_t d = done.fetch_add(items, std::memory_order_relaxed) + items;
    progress.report((pass + static_cast<double>(d) / static_cast<double>(total)) / 3.0);
  };
  auto grain_for = [&](std::int64_t items) { return std::max<std::int64_t>(1, items / (nthreads * 32)); };

  // Pass x: 1D distance from the bit runs, squared.
  const std::int64_t rows = ny * nz;
  parallel_for(0, rows, grain_for(rows), nthreads, [&](std::int64_t r0, std::int64_t r1) {
    progress.check_cancelled();
    for (std::int64_t r = r0; r < r1; ++r) {
      const std::int64_t j = r % ny, k = r / ny;
      std::uint32_t* line = data + static_cast<std::size_t>(k) * slab + static_cast<std::size_t>(j * nx);
      for_each_run(solid.row(j, k), solid.row_words(), nx, [line](std::int64_t a, std::int64_t b) {
        for (std::int64_t i = a; i < b; ++i) {
          const std::int64_t d = std::min(i - a + 1, b - i);
          line[i] = static_cast<std::uint32_t>(d * d);
        }
      });
    }
    tick(r1 - r0, rows, 0);
  });

  // Passes y and z: the same gather / solve / scatter over blocks of x-adjacent
  // lines; `stride` is the distance between consecutive voxels along the axis.
  const std::int64_t blocks = (nx + kBlock - 1) / kBlock;
  auto strided_pass = [&](std::int64_t n, std::size_t stride, std::int64_t lines_per_block_row,
                          auto&& base_of, int pass) {
    const std::int64_t items = lines_per_block_row * blocks;
    done.store(0);
    parallel_for(0, items, grain_for(items), nthreads, [&](std::int64_t i0, std::int64_t i1) {
      progress.check_cancelled();
      const std::int64_t len = n + 2;
      std::vector<std::uint32_t> buf(static_cast<std::size_t>(kBlock * len), 0u);
      LineSolver solver(n);
      for (std::int64_t item = i0; item < i1; ++item) {
        const std::int64_t line_index = item / blocks;
        const std::int64_t x0 = (item % blocks) * kBlock;
        const std::int64_t width = std::min(kBlock, nx - x0);
        std::uint32_t* base = data + base_of(line_index) + static_cast<std::size_t>(x0);
        bool any = false;
        for (std::int64_t p = 0; p < n; ++p) {
          const std::uint32_t* src = base + static_cast<std::size_t>(p) * stride;
          for (std::int64_t c = 0; c < width; ++c) {
            buf[static_cast<std::size_t>(c * len + p + 1)] = src[c];
            any |= src[c] != 0;
          }
        }
        if (!any) continue;  // all empty: distances stay 0
        for (std::int64_t c = 0; c < width; ++c) {
          std::uint32_t* line = buf.data() + c * len;
          line[0] = 0;
          line[n + 1] = 0;
          solver.solve(line, n);
        }
        for (std::int64_t p = 0; p < n; ++p) {
          std::uint32_t* dst = base + static_cast<std::size_t>(p) * stride;
          for (std::int64_t c = 0; c < width; ++c) dst[c] = buf[static_cast<std::size_t>(c * len + p + 1)];
        }
      }
      tick(i1 - i0, items, pass);
    });
  };
  // y: one block row per z-slab; z: one block row per y.
  strided_pass(ny, static_cast<std::size_t>(nx), nz,
               [&](std::int64_t k) { return static_cast<std::size_t>(k) * slab; }, 1);
  strided_pass(nz, slab, ny, [&](std::int64_t j) { return static_cast<std::size_t>(j * nx); }, 2);
  progress.report(1.0);
  return out;
}

}  // namespace detail

DenseVolume<std::uint32_t> squared_distance_transform(const BitVolume& solid, int threads, JobControl* control) {
  return detail::squared_distance_transform(solid, threads, detail::ProgressSpan{control, 0.0, 1.0});
}

}  // namespace voxd
