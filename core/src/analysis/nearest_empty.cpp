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
//
// Passes y and z touch only what can change. For the nearest empty voxel,
// a block's lines are read from just before their first filled voxel to
// just after their last: the empty voxels beyond are their own sites and
// are left as pass x wrote them (on a part in its padded grid, half the
// grid or more). For the nearest marked voxel (a wall's medial voxels, a
// sheet or a ring: a few rows of a layer), only the rows holding a mark
// have sites after pass x and only the layers holding one after pass y, so
// pass y reads only those rows and pass z only those layers, each solving
// the envelope of those sites alone; pass z writes, with `wanted`, only
// from the lines' first wanted voxel to their last, skipping blocks with
// none.
//
// Every pass keeps the earlier of two equally near sites along its axis,
// so a voxel's answer is, of its nearest sites, the first in memory order
// (lowest z, then y, then x), however the passes are cut.
#include "voxd/detail/nearest_empty.h"

#include <algorithm>
#include <vector>

#include "analysis/lower_envelope.h"
#include "analysis/progress_span.h"
#include "analysis/row_runs.h"
#include "voxd/error.h"
#include "voxd/parallel.h"

namespace voxd::detail {
namespace {

constexpr std::int64_t kBlock = 16;  // uint32 lines gathered together: one cache line

// g of a voxel with no site in reach yet: its parabola is left out.
constexpr std::int64_t kNoSite = std::int64_t{1} << 60;

// Where the set bits of a volume lie along the lines of passes y and z, a
// block of kBlock lines at a time: for pass y, line (x, *, k), the first and
// last row j of layer k with a set bit in the block's columns; for pass z,
// line (x, j, *), the first and last layer k. A block with none has
// first > last.
struct SetExtents {
  struct Span {
    std::int32_t first = INT32_MAX, last = -1;
  };
  std::int64_t blocks = 0;
  std::vector<Span> y, z;  // y: [k * blocks + b], z: [j * blocks + b]
};

// The bits of row `row` in block b's columns.
inline std::uint64_t block_bits(const std::uint64_t* row, std::int64_t b, std::int64_t nx) {
  const std::int64_t x0 = b * kBlock;
  const std::int64_t width = std::min(kBlock, nx - x0);
  const std::uint64_t mask = width >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << width) - 1;
  return (row[x0 >> 6] >> (x0 & 63)) & mask;
}

SetExtents set_extents(const BitVolume& v, int nthreads) {
  static_assert(64 % kBlock == 0, "a block's columns lie in one word");
  const glm::i64vec3 d = v.grid().dims;
  SetExtents e;
  e.blocks = (d.x + kBlock - 1) / kBlock;
  e.y.resize(static_cast<std::size_t>(d.z * e.blocks));
  e.z.resize(static_cast<std::size_t>(d.y * e.blocks));
  // Each span is written by one thread: pass y's by layer, pass z's by row.
  parallel_for(0, d.z, std::max<std::int64_t>(1, d.z / (nthreads * 8)), nthreads, [&](std::int64_t k0, std::int64_t k1) {
    for (std::int64_t k = k0; k < k1; ++k)
      for (std::int64_t j = 0; j < d.y; ++j) {
        const std::uint64_t* row = v.row(j, k);
        for (std::int64_t b = 0; b < e.blocks; ++b) {
          if (!block_bits(row, b, d.x)) continue;
          SetExtents::Span& s = e.y[static_cast<std::size_t>(k * e.blocks + b)];
          s.first = std::min(s.first, static_cast<std::int32_t>(j));
          s.last = static_cast<std::int32_t>(j);
        }
      }
  });
  parallel_for(0, d.y, std::max<std::int64_t>(1, d.y / (nthreads * 8)), nthreads, [&](std::int64_t j0, std::int64_t j1) {
    for (std::int64_t k = 0; k < d.z; ++k)
      for (std::int64_t j = j0; j < j1; ++j) {
        const std::uint64_t* row = v.row(j, k);
        for (std::int64_t b = 0; b < e.blocks; ++b) {
          if (!block_bits(row, b, d.x)) continue;
          SetExtents::Span& s = e.z[static_cast<std::size_t>(j * e.blocks + b)];
          s.first = std::min(s.first, static_cast<std::int32_t>(k));
          s.last = static_cast<std::int32_t>(k);
        }
      }
  });
  return e;
}

// The feature transform of the sites: the set bits of `bits` if
// `sites_are_set`, else its clear bits, and with `outside_is_site`
// everything outside the grid. Voxels with no site get kNoNearestVoxel.
// With `wanted`, only its set voxels are sure of their answer (the others
// may keep pass y's).
void nearest_sites(const BitVolume& solid, bool sites_are_set, bool outside_is_site, const BitVolume* wanted,
                   DenseVolume<std::uint32_t>& out, int threads, JobControl* control, double progress_from,
                   double progress_to) {
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
  // Sites set in the bits (marked voxels, not outside): after pass x only
  // the rows holding one have sites, and after pass y only the layers
  // holding one, so passes x and y read only those rows and pass z only
  // those layers. Else pass x writes every voxel, and a new volume starts
  // uninitialized (a kept block's pages are not faulted in again).
  const bool listed_sites = sites_are_set && !outside_is_site;
  if (out.grid().dims != grid.dims)
    out = listed_sites ? DenseVolume<std::uint32_t>(grid, 0u)
                       : DenseVolume<std::uint32_t>(grid, DenseVolume<std::uint32_t>::Uninitialized{});
  if (grid.voxel_count() == 0) return;
  const int nthreads = threads > 0 ? threads : default_thread_count();
  const ProgressSpan progress{control, progress_from, progress_to};
  std::uint32_t* data = out.values().data();
  const std::size_t slab = out.slab_size();
  auto grain_for = [&](std::int64_t items) { return std::max<std::int64_t>(1, items / (nthreads * 32)); };

  auto has_bits = [&](const std::uint64_t* row) {
    for (std::int64_t w = 0; w < solid.row_words(); ++w)
      if (row[w] != 0) return true;
    return false;
  };
  std::vector<std::vector<std::int64_t>> site_rows(listed_sites ? static_cast<std::size_t>(nz) : 0);
  std::vector<std::int64_t> site_layers;
  if (listed_sites) {
    parallel_for(0, nz, std::max<std::int64_t>(1, nz / (nthreads * 8)), nthreads, [&](std::int64_t k0, std::int64_t k1) {
      for (std::int64_t k = k0; k < k1; ++k)
        for (std::int64_t j = 0; j < ny; ++j)
          if (has_bits(solid.row(j, k))) site_rows[static_cast<std::size_t>(k)].push_back(j);
    });
    for (std::int64_t k = 0; k < nz; ++k)
      if (!site_rows[static_cast<std::size_t>(k)].empty()) site_layers.push_back(k);
  }

  // Pass x.
  const std::int64_t rows = ny * nz;
  parallel_for(0, rows, grain_for(rows), nthreads, [&](std::int64_t r0, std::int64_t r1) {
    progress.check_cancelled();
    for (std::int64_t r = r0; r < r1; ++r) {
      const std::int64_t j = r % ny, k = r / ny;
      if (listed_sites && !has_bits(solid.row(j, k))) continue;  // read by no pass
      std::uint32_t* line = data + static_cast<std::size_t>(k) * slab + static_cast<std::size_t>(j * nx);
      for (std::int64_t i = 0; i < nx; ++i) line[i] = padded.of(i, j, k);
      for_each_row_run(solid.row(j, k), solid.row_words(), nx, sites_are_set, [&](std::int64_t a, std::int64_t b) {
        const bool before = outside_is_site || a > 0, after = outside_is_site || b < nx;
        for (std::int64_t i = a; i < b; ++i) {
          const bool take_before = before && (!after || i - a + 1 <= b - i);
          line[i] = take_before ? padded.of(a - 1, j, k) : after ? padded.of(b, j, k) : kNoNearestVoxel;
        }
      });
    }
  });
  progress.report(1.0 / 3.0);

  // Which part [lo, hi) of a block's lines a pass writes (none when
  // lo >= hi). The nearest empty voxel: from the empty voxel before the
  // lines' first filled one to the one after their last (the runs of
  // filled voxels and the empty voxels bounding them; outside, the grid's
  // edge bounds them), also all it reads. The nearest marked voxel: in pass
  // y the whole lines of layers with sites; in pass z from the first
  // wanted voxel to the last (without `wanted`, whole lines), reading the
  // layers with sites.
  const std::int64_t blocks = (nx + kBlock - 1) / kBlock;
  const bool sites_are_empty = !sites_are_set && outside_is_site;
  const BitVolume* extents_of = sites_are_empty ? &solid : wanted;
  const SetExtents extents = extents_of ? set_extents(*extents_of, nthreads) : SetExtents{};
  auto part_of = [&](int axis, std::int64_t n, std::int64_t line_index,
                     std::int64_t block) -> std::pair<std::int64_t, std::int64_t> {
    if (listed_sites && axis == 1 && site_rows[static_cast<std::size_t>(line_index)].empty()) return {0, 0};
    if (!sites_are_empty && (axis == 1 || !wanted)) return {0, n};
    const SetExtents::Span& span =
        (axis == 1 ? extents.y : extents.z)[static_cast<std::size_t>(line_index * extents.blocks + block)];
    if (span.first > span.last) return {0, 0};
    if (!sites_are_empty) return {span.first, span.last + 1};
    return {std::max<std::int64_t>(0, span.first - 1), std::min<std::int64_t>(n, span.last + 2)};
  };

  // Passes y and z over blocks of kBlock x-adjacent lines. `point(c, p)`
  // gives the coordinates of line c's voxel p (p = -1 and n: outside).
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
      std::vector<std::int64_t> site_at(static_cast<std::size_t>(len)), site_g(static_cast<std::size_t>(len)),
          site_t(static_cast<std::size_t>(len));
      for (std::int64_t item = i0; item < i1; ++item) {
        const std::int64_t line_index = item / blocks;
        const auto [lo, hi] = part_of(axis, n, line_index, item % blocks);
        if (lo >= hi) continue;
        const std::int64_t x0 = (item % blocks) * kBlock;
        const std::int64_t width = std::min(kBlock, nx - x0);
        std::uint32_t* base = data + base_of(line_index) + static_cast<std::size_t>(x0);
        // Listed sites: only the rows (pass y) or layers (pass z) holding
        // them are read; the others hold none and may not have been written.
        const std::vector<std::int64_t>* listed =
            !listed_sites ? nullptr : axis == 1 ? &site_rows[static_cast<std::size_t>(line_index)] : &site_layers;
        auto gather = [&](std::int64_t p) {
          const std::uint32_t* src = base + static_cast<std::size_t>(p) * stride;
          for (std::int64_t c = 0; c < width; ++c) buf[static_cast<std::size_t>(c * len + p + 1)] = src[c];
        };
        if (listed) {
          for (std::int64_t p : *listed) gather(p);
        } else {
          for (std::int64_t p = lo; p < hi; ++p) gather(p);
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
          // Outside: a site at distance 0, or none.
          g[0] = outside_is_site ? 0 : kNoSite;
          g[static_cast<std::size_t>(n + 1)] = g[0];
          // A voxel that is its own site costs no decode; a line with no
          // site anywhere (outside or in) stays as it is.
          const glm::i64vec3 origin = point(0);
          const std::int64_t step = axis == 1 ? padded.px : padded.px * padded.py;
          const std::int64_t own0 = padded.of(origin.x, origin.y, origin.z);
          const std::int64_t own_row0 = own0 / padded.px;  // the row of p = 0's voxel
          bool any_site = outside_is_site;
          auto solve_g = [&](std::int64_t p) {
            const std::uint32_t at = line[p + 1];
            if (at == kNoNearestVoxel) {
              g[static_cast<std::size_t>(p + 1)] = kNoSite;
              return;
            }
            any_site = true;
            const std::int64_t own = own0 + p * step;
            if (at == static_cast<std::uint32_t>(own)) {
              g[static_cast<std::size_t>(p + 1)] = 0;
              return;
            }
            // Pass x found sites along the voxel's row, pass y within its
            // layer: the offset along x is the indices' difference, and
            // across a layer one division tells the row apart.
            std::int64_t dx = static_cast<std::int64_t>(at) - own, dy = 0;
            if (axis == 2) {
              dy = padded.row_of(at) - (own_row0 + p * padded.py);
              dx -= dy * padded.px;
            }
            g[static_cast<std::size_t>(p + 1)] = dx * dx + dy * dy;
          };
          if (listed) {
            // The listed sites, then the envelope of those alone, read only
            // where it is written.
            int count = 0;
            for (std::int64_t p : *listed) {
              solve_g(p);
              if (g[static_cast<std::size_t>(p + 1)] == kNoSite) continue;
              site_at[static_cast<std::size_t>(count)] = p;
              site_g[static_cast<std::size_t>(count)] = g[static_cast<std::size_t>(p + 1)];
              won[static_cast<std::size_t>(count++)] = line[p + 1];
            }
            if (count == 0) std::fill(line + lo + 1, line + hi + 1, kNoNearestVoxel);
            lower_envelope_of_sites(site_at.data(), site_g.data(), count, n, s.data(), site_t.data(), lo, hi,
                                    [&](std::int64_t u, int k) { line[u + 1] = won[static_cast<std::size_t>(k)]; });
            continue;
          }
          for (std::int64_t p = lo; p < hi; ++p) solve_g(p);
          if (!any_site) continue;
          // Line positions p + 1 for p in [lo, hi); a run of filled voxels
          // ends inside them or at the outside entry n + 1.
          std::int64_t i = lo + 1;
          while (i <= hi) {
            if (g[static_cast<std::size_t>(i)] == 0) {
              ++i;
              continue;
            }
            const std::int64_t a = i;
            while (i <= hi && g[static_cast<std::size_t>(i)] != 0) ++i;
            const std::int64_t b = i;
            const int m = static_cast<int>(b - a + 2);
            lower_envelope<true>(g.data() + a - 1, m, s.data(), t.data(), kNoSite, [&](int u, int i) { site[u] = i; });
            // Winners read from the sites before any is overwritten.
            for (int u = 1; u < m - 1; ++u)
              won[static_cast<std::size_t>(u)] = site[u] < 0 ? kNoNearestVoxel : line[a - 1 + site[u]];
            for (int u = 1; u < m - 1; ++u) line[a - 1 + u] = won[static_cast<std::size_t>(u)];
          }
        }
        for (std::int64_t p = lo; p < hi; ++p) {
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
}

}  // namespace

DenseVolume<std::uint32_t> nearest_empty_voxels(const BitVolume& solid, int threads, JobControl* control,
                                                double progress_from, double progress_to) {
  DenseVolume<std::uint32_t> out;
  nearest_sites(solid, false, true, nullptr, out, threads, control, progress_from, progress_to);
  return out;
}

void nearest_marked_voxels(const BitVolume& marked, DenseVolume<std::uint32_t>& out, const BitVolume* wanted,
                           int threads, JobControl* control, double progress_from, double progress_to) {
  nearest_sites(marked, true, false, wanted, out, threads, control, progress_from, progress_to);
}

}  // namespace voxd::detail
