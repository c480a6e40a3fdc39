// Feature transform: the distance transform's three passes, each carrying
// the nearest site's padded index (voxd/detail/nearest_empty.h).
//
// Pass x reads the bit rows: inside a run of filled voxels [a, b) the
// nearest empty voxel along the row is a - 1 or b (either may be outside).
// Passes y and z solve the lower envelope of the parabolas
// (u - p)^2 + g(p) along their axis, where g(p) is the squared distance
// from site p to the nearest empty voxel the previous passes found for it;
// the winning site hands its voxel on. As in the distance transform, an
// empty voxel (g = 0) hides everything beyond it, so each run of filled
// voxels is solved between its two bounding empty voxels.
#include "voxd/detail/nearest_empty.h"

#include <algorithm>
#include <vector>

#include "analysis/progress_span.h"
#include "analysis/row_runs.h"
#include "voxd/error.h"
#include "voxd/parallel.h"

namespace voxd::detail {
namespace {

constexpr std::int64_t kBlock = 16;  // uint32 lines gathered together: one cache line

inline std::int64_t floor_div(std::int64_t a, std::int64_t b) {
  const std::int64_t q = a / b;
  return (a % b != 0 && a < 0) ? q - 1 : q;
}

// Lower envelope of (u - i)^2 + g[i] over sites i in [0, m); site[u] gets
// the winning i for every u in [0, m). Scratch s and t hold m entries.
void envelope_sites(const std::int64_t* g, int m, int* site, int* s, int* t) {
  auto f = [g](std::int64_t x, std::int64_t i) { return (x - i) * (x - i) + g[i]; };
  auto sep = [g](std::int64_t i, std::int64_t u) { return floor_div(u * u - i * i + g[u] - g[i], 2 * (u - i)); };
  int q = 0;
  s[0] = 0;
  t[0] = 0;
  for (int u = 1; u < m; ++u) {
    while (q >= 0 && f(t[q], s[q]) > f(t[q], u)) --q;
    if (q < 0) {
      q = 0;
      s[0] = u;
    } else {
      const std::int64_t w = 1 + sep(s[q], u);
      if (w < m) {
        ++q;
        s[q] = u;
        t[q] = static_cast<int>(w);
      }
    }
  }
  for (int u = m - 1; u >= 0; --u) {
    site[u] = s[q];
    if (u == t[q]) --q;
  }
}

}  // namespace

DenseVolume<std::uint32_t> nearest_empty_voxels(const BitVolume& solid, int threads, JobControl* control,
                                                double progress_from, double progress_to) {
  const Grid& grid = solid.grid();
  const std::int64_t nx = grid.dims.x, ny = grid.dims.y, nz = grid.dims.z;
  const PaddedIndex padded(grid);
  if (static_cast<double>(padded.px) * static_cast<double>(padded.py) * static_cast<double>(padded.pz) >
      4294967295.0) {
    throw Error(ErrorCode::limit_exceeded,
                "wall thickness works on grids of at most 2^32 voxels with one layer of padding (about 1600^3); "
                "this grid is " + std::to_string(nx) + " x " + std::to_string(ny) + " x " + std::to_string(nz) +
                    ": use a larger voxel size");
  }
  DenseVolume<std::uint32_t> out(grid, 0u);
  if (grid.voxel_count() == 0) return out;
  const int nthreads = threads > 0 ? threads : default_thread_count();
  const ProgressSpan progress{control, progress_from, progress_to};
  std::uint32_t* data = out.values().data();
  const std::size_t slab = out.slab_size();
  auto grain_for = [&](std::int64_t items) { return std::max<std::int64_t>(1, items / (nthreads * 32)); };

  // Pass x.
  const std::int64_t rows = ny * nz;
  parallel_for(0, rows, grain_for(rows), nthreads, [&](std::int64_t r0, std::int64_t r1) {
    progress.check_cancelled();
    for (std::int64_t r = r0; r < r1; ++r) {
      const std::int64_t j = r % ny, k = r / ny;
      std::uint32_t* line = data + static_cast<std::size_t>(k) * slab + static_cast<std::size_t>(j * nx);
      for (std::int64_t i = 0; i < nx; ++i) line[i] = padded.of(i, j, k);
      for_each_row_run(solid.row(j, k), solid.row_words(), nx, false, [&](std::int64_t a, std::int64_t b) {
        for (std::int64_t i = a; i < b; ++i) line[i] = padded.of(i - a + 1 <= b - i ? a - 1 : b, j, k);
      });
    }
  });
  progress.report(1.0 / 3.0);

  // Passes y and z over blocks of kBlock x-adjacent lines. `point(c, p)`
  // gives the coordinates of line c's voxel p (p = -1 and n: outside).
  const std::int64_t blocks = (nx + kBlock - 1) / kBlock;
  auto strided_pass = [&](int axis, std::int64_t n, std::size_t stride, std::int64_t lines_per_block_row,
                          auto&& base_of, int pass) {
    const std::int64_t items = lines_per_block_row * blocks;
    parallel_for(0, items, grain_for(items), nthreads, [&](std::int64_t i0, std::int64_t i1) {
      progress.check_cancelled();
      const std::int64_t len = n + 2;
      std::vector<std::uint32_t> buf(static_cast<std::size_t>(kBlock * len));
      std::vector<std::int64_t> g(static_cast<std::size_t>(len));
      std::vector<int> site(static_cast<std::size_t>(len)), s(static_cast<std::size_t>(len)),
          t(static_cast<std::size_t>(len));
      std::vector<std::uint32_t> won(static_cast<std::size_t>(len));
      for (std::int64_t item = i0; item < i1; ++item) {
        const std::int64_t line_index = item / blocks;
        const std::int64_t x0 = (item % blocks) * kBlock;
        const std::int64_t width = std::min(kBlock, nx - x0);
        std::uint32_t* base = data + base_of(line_index) + static_cast<std::size_t>(x0);
        for (std::int64_t p = 0; p < n; ++p) {
          const std::uint32_t* src = base + static_cast<std::size_t>(p) * stride;
          for (std::int64_t c = 0; c < width; ++c) buf[static_cast<std::size_t>(c * len + p + 1)] = src[c];
        }
        for (std::int64_t c = 0; c < width; ++c) {
          std::uint32_t* line = buf.data() + c * len;
          // The line's fixed coordinates, from its first voxel's own index.
          glm::i64vec3 at{x0 + c, 0, 0};
          if (axis == 1) at.z = line_index;
          else at.y = line_index;
          auto point = [&](std::int64_t p) {
            glm::i64vec3 q = at;
            q[axis] = p;
            return q;
          };
          line[0] = padded.of(point(-1).x, point(-1).y, point(-1).z);
          line[n + 1] = padded.of(point(n).x, point(n).y, point(n).z);
          g[0] = 0;
          g[static_cast<std::size_t>(n + 1)] = 0;
          for (std::int64_t p = 0; p < n; ++p) {
            const glm::i64vec3 d = padded.at(line[p + 1]) - point(p);
            g[static_cast<std::size_t>(p + 1)] = d.x * d.x + d.y * d.y + d.z * d.z;
          }
          std::int64_t i = 1;
          while (i <= n) {
            if (g[static_cast<std::size_t>(i)] == 0) {
              ++i;
              continue;
            }
            const std::int64_t a = i;
            while (g[static_cast<std::size_t>(i)] != 0) ++i;
            const std::int64_t b = i;
            const int m = static_cast<int>(b - a + 2);
            envelope_sites(g.data() + a - 1, m, site.data(), s.data(), t.data());
            // Winners read from the sites before any is overwritten.
            for (int u = 1; u < m - 1; ++u) won[static_cast<std::size_t>(u)] = line[a - 1 + site[u]];
            for (int u = 1; u < m - 1; ++u) line[a - 1 + u] = won[static_cast<std::size_t>(u)];
          }
        }
        for (std::int64_t p = 0; p < n; ++p) {
          std::uint32_t* dst = base + static_cast<std::size_t>(p) * stride;
          for (std::int64_t c = 0; c < width; ++c) dst[c] = buf[static_cast<std::size_t>(c * len + p + 1)];
        }
      }
    });
    progress.report((pass + 1) / 3.0);
  };
  strided_pass(1, ny, static_cast<std::size_t>(nx), nz,
               [&](std::int64_t k) { return static_cast<std::size_t>(k) * slab; }, 1);
  strided_pass(2, nz, slab, ny, [&](std::int64_t j) { return static_cast<std::size_t>(j * nx); }, 2);
  return out;
}

}  // namespace voxd::detail
