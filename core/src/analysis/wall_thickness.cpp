// Wall thickness (voxd/analysis/wall_thickness.h): medial pairs from the
// feature transform, each voxel given the wall of its nearest medial voxel,
// the junctions of walls painted by the walls' balls largest first, and the
// few voxels left filled from their neighbours.
#include "voxd/analysis/wall_thickness.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <mutex>
#include <vector>

#include "analysis/ball_painting.h"
#include "analysis/progress_span.h"
#include "analysis/row_runs.h"
#include "voxd/detail/bit_window.h"
#include "voxd/detail/nearest_empty.h"
#include "voxd/parallel.h"

namespace voxd {
namespace {

using detail::Ball;
using detail::PaddedIndex;

inline std::int64_t norm2(const glm::i64vec3& v) { return v.x * v.x + v.y * v.y + v.z * v.z; }

// Whether voxel p is filled; outside the grid nothing is.
inline bool filled_at(const BitVolume& solid, const glm::i64vec3& p) {
  const glm::i64vec3 d = solid.grid().dims;
  return p.x >= 0 && p.y >= 0 && p.z >= 0 && p.x < d.x && p.y < d.y && p.z < d.z && solid.get(p.x, p.y, p.z);
}

// The surface near an empty voxel f next to the solid, fitted from the
// voxels around it: the inward normal (towards the solid's voxels within
// two voxels) and the plane's offset from f along it. The offset is where
// the window's filled voxels end when the window is ordered along the
// normal: in a slab 3 voxels thick and 2 voxels in radius around f, the K
// filled voxels should be the K farthest along the normal; the plane lies
// halfway between the K-th and the next. On a face along a grid axis that
// is exactly half a voxel (the voxel faces), and on a tilted face it
// follows the face to a fraction of a voxel instead of resting on the
// nearest empty centre, which lies anywhere from 0 to 1 voxel off it.
struct SurfaceFit {
  glm::dvec3 normal{0.0};
  double offset = 0.5;
  bool valid = false;
};

// The offsets of the fits' windows, in the order the fits visit them (z,
// then y, then x): those within 2 voxels of the centre with the unit
// direction to each (for the normal), and those within sqrt(6) (the slab's
// window: a voxel more than 1.5 along the normal or 2 across it is more
// than sqrt(1.5^2 + 2^2) = 2.5 away, and the squared lengths are integers).
// Tables of the same doubles the loops computed, so the same sums.
struct WindowOffset {
  glm::i64vec3 o{0};
  glm::dvec3 d{0.0};  // o, or o / |o| in the ball's table
  int row = 0, bit = 0;  // where BitWindow5 reads it
};

struct FitWindows {
  std::vector<WindowOffset> ball, slab;
  FitWindows() {
    for (int z = -2; z <= 2; ++z)
      for (int y = -2; y <= 2; ++y)
        for (int x = -2; x <= 2; ++x) {
          const int r2 = x * x + y * y + z * z;
          const int row = (z + 2) * 5 + (y + 2), bit = x + 2;
          if (r2 > 0 && r2 <= 4)
            ball.push_back({{x, y, z}, glm::dvec3(x, y, z) / std::sqrt(static_cast<double>(r2)), row, bit});
          if (r2 <= 6) slab.push_back({{x, y, z}, glm::dvec3(x, y, z), row, bit});
        }
  }
};

const FitWindows& fit_windows() {
  static const FitWindows windows;
  return windows;
}

// The plane's offset from f along `normal` (inward), where the window's
// filled voxels end (see SurfaceFit).
double plane_offset(const detail::BitWindow5& window, const glm::dvec3& normal) {
  double offset = 0.5;
  double projections[125];
  int n = 0, k = 0;
  for (const WindowOffset& w : fit_windows().slab) {
    const glm::dvec3& o = w.d;
    const double along = o.x * normal.x + o.y * normal.y + o.z * normal.z;
    const glm::dvec3 across = o - along * normal;
    if (std::abs(along) > 1.5 || across.x * across.x + across.y * across.y + across.z * across.z > 4.0) continue;
    projections[n++] = along;
    k += window.get(w.row, w.bit) ? 1 : 0;
  }
  if (k > 0 && k < n) {
    std::nth_element(projections, projections + (n - k), projections + n);
    const double lowest_filled = projections[n - k];
    const double highest_empty = *std::max_element(projections, projections + (n - k));
    offset = 0.5 * (lowest_filled + highest_empty);
  }
  return offset;
}

SurfaceFit fit_surface(const BitVolume& solid, const glm::i64vec3& f) {
  SurfaceFit fit;
  const detail::BitWindow5 window(solid, f);
  glm::dvec3 g{0.0};
  for (const WindowOffset& w : fit_windows().ball)
    if (window.get(w.row, w.bit)) g += w.d;
  const double len = std::sqrt(g.x * g.x + g.y * g.y + g.z * g.z);
  if (len < 1e-9) return fit;
  fit.normal = g / len;
  fit.offset = plane_offset(window, fit.normal);
  fit.valid = true;
  return fit;
}

// The fits of the empty voxels a thread met last: every empty voxel on a
// wall's face is fitted for each pair of medial voxels that sees it
// (typically several), so a small direct-mapped cache of the fits saves
// most of them. One per thread: no locking, same results.
class FitCache {
 public:
  explicit FitCache(const BitVolume& solid) : solid_(solid), padded_(solid.grid()), keys_(kSlots, kEmpty), fits_(kSlots) {}
  const BitVolume& solid() const { return solid_; }
  const SurfaceFit& fit(const glm::i64vec3& f) {
    const std::uint32_t key = padded_.of(f.x, f.y, f.z);
    const std::size_t slot = (key * 2654435761u) >> (32 - kBits);
    if (keys_[slot] != key) {
      keys_[slot] = key;
      fits_[slot] = fit_surface(solid_, f);
    }
    return fits_[slot];
  }

 private:
  static constexpr int kBits = 16;
  static constexpr std::size_t kSlots = std::size_t{1} << kBits;
  static constexpr std::uint32_t kEmpty = 0xFFFFFFFFu;  // no padded index is this (see nearest_empty.h)
  const BitVolume& solid_;
  PaddedIndex padded_;
  std::vector<std::uint32_t> keys_;
  std::vector<SurfaceFit> fits_;
};

// The two faces' fits a wall's thickness is measured between, and the
// direction across it (`n`, from side a to side b), given the fits of the
// empty voxels fp and fq on its two sides. On a curved face the voxels are
// a staircase, and a window at one of its steps sees the step's riser: the
// fitted normal leans towards it (25° on a tube's wall 5° off a grid axis).
// Both faces of a wall turned alike lean alike and still look parallel, and
// planes along the leaning normal are closer than the faces by its cosine
// (two voxels on a wall 30 thick). Across a thick wall the chord between
// the two nearest empty voxels knows the direction better, to about
// atan(2 / length): on a wall at least kChordMinLength voxels across, where
// the fits are parallel (within 30°: the risers also tilt the two fits
// apart, by 21° on a tube 60 voxels thick turned 71°/16°) but their mean
// leaves the chord by more than that (and 8°), the faces are placed along
// the chord. A tapering wall's fits are not parallel but their mean is its
// bisector, which the chord follows: it keeps its fits. Thinner walls keep their
// fits: there the chord's lattice error is the larger, and the lean costs
// under a voxel. Measured with bench/wall_accuracy (docs/benchmarks.md,
// issue #35): tubes and spherical shells 12 to 57 voxels thick, turned or
// not, read within ±1 voxel of the mesh's ray thickness at every sampled
// point, from 73-98% before; with the 30° (from 20°) the thin stripes across
// a 60-voxel tube and by a cup's floor are gone.
constexpr double kChordMinLength = 12.0;

std::pair<SurfaceFit, SurfaceFit> along_chord(const BitVolume& solid, const SurfaceFit& a, const SurfaceFit& b,
                                              const glm::i64vec3& fp, const glm::i64vec3& fq, glm::dvec3& n) {
  constexpr double kPi = 3.14159265358979323846;
  const glm::dvec3 chord(fq - fp);
  const double length = std::sqrt(chord.x * chord.x + chord.y * chord.y + chord.z * chord.z);
  if (length < kChordMinLength) return {a, b};
  const double parallel = -(a.normal.x * b.normal.x + a.normal.y * b.normal.y + a.normal.z * b.normal.z);
  const glm::dvec3 m = chord / length;
  const double lean = n.x * m.x + n.y * m.y + n.z * m.z;
  if (parallel < std::cos(30.0 * kPi / 180.0) || lean >= std::cos(std::max(8.0 * kPi / 180.0, std::atan(2.0 / length))))
    return {a, b};
  n = m;
  return {SurfaceFit{m, plane_offset(detail::BitWindow5(solid, fp), m), true}, SurfaceFit{-m, plane_offset(detail::BitWindow5(solid, fq), -m), true}};
}

// The wall between the empty voxels fp and fq on its two sides, seen from
// the medial voxels p and q (p == q for a wall one voxel thick): its
// thickness in voxels if the two surfaces face each other, else a negative
// value. Facing: the fitted surface normals are at least the separation
// angle apart; or, where a surface has no normal of its own (a concave
// edge, where a rib meets a wall), the directions from p and q to fp and fq
// are, if both are at least two voxels long (shorter ones are the lattice's
// steps on a convex edge, not a direction).
double wall_between(FitCache& fits, const glm::i64vec3& p, const glm::i64vec3& q, const glm::i64vec3& fp,
                    const glm::i64vec3& fq, double cos_separation) {
  const SurfaceFit a = fits.fit(fp), b = fits.fit(fq);
  if (a.valid && b.valid &&
      a.normal.x * b.normal.x + a.normal.y * b.normal.y + a.normal.z * b.normal.z <= cos_separation) {
    // Across the wall (n, from side a to side b) through the medial
    // location c, between the two fitted planes. Where the faces are not
    // parallel (a tapering wall) this is the wall's section at c, not at the
    // fits' footpoints, which lie towards the thin end.
    glm::dvec3 n = a.normal - b.normal;
    n /= std::sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
    const auto [fa, fb] = along_chord(fits.solid(), a, b, fp, fq, n);
    const glm::dvec3 c = 0.5 * (glm::dvec3(p) + glm::dvec3(q));
    auto crossing = [&](const SurfaceFit& fit, const glm::i64vec3& f) {
      const glm::dvec3 on_plane = glm::dvec3(f) + fit.offset * fit.normal - c;
      return (on_plane.x * fit.normal.x + on_plane.y * fit.normal.y + on_plane.z * fit.normal.z) /
             (n.x * fit.normal.x + n.y * fit.normal.y + n.z * fit.normal.z);
    };
    return std::max(0.5, crossing(fb, fq) - crossing(fa, fp));
  }
  // Where a rib meets a wall the fitted normals are still more than 120°
  // apart (the concave corner's normal is the bisector); on a convex edge
  // they are not.
  if (!a.valid || !b.valid || a.normal.x * b.normal.x + a.normal.y * b.normal.y + a.normal.z * b.normal.z > -0.5)
    return -1.0;
  const glm::i64vec3 u = fp - p, w = fq - q;
  const std::int64_t u2 = norm2(u), w2 = norm2(w);
  if (u2 < 16 || w2 < 16) return -1.0;
  // Only where a fit is not to be trusted: at a concave edge the fitted
  // normal is the corner's bisector, far from the direction to the voxel.
  // Where both fits agree with their directions (within 30°) the surfaces
  // are what the fits say, and they do not face each other: a thread's
  // flanks near its flat crest, whose lattice directions are off by 15°.
  auto agrees = [](const SurfaceFit& fit, const glm::i64vec3& v, std::int64_t v2) {
    const double c = -(fit.normal.x * static_cast<double>(v.x) + fit.normal.y * static_cast<double>(v.y) +
                       fit.normal.z * static_cast<double>(v.z)) / std::sqrt(static_cast<double>(v2));
    return c >= 0.866;
  };
  if (agrees(a, u, u2) && agrees(b, w, w2)) return -1.0;
  const auto dot = static_cast<double>(u.x * w.x + u.y * w.y + u.z * w.z);
  if (dot > cos_separation * std::sqrt(static_cast<double>(u2) * static_cast<double>(w2))) return -1.0;
  return std::sqrt(static_cast<double>(norm2(fq - fp))) - 1.0;
}

// The segment across the wall between its two surfaces' empty voxels
// (voxel coordinates; -1 or dims for the outside).
struct Chord {
  glm::i32vec3 from{0}, to{0};
};

struct Medial {
  Ball ball;
  Chord chord;
  // Squared depth a voxel of this wall may have: the ball's radius and a
  // voxel, (r + 1)^2 (a wall's voxels beside its medial ones on the lattice).
  std::int64_t reach2 = 0;
};

// Which medial record a medial voxel has: its rank among the set bits of
// `centres` in memory order (a count per row, then the bits before it in
// its row) indexes the records sorted by voxel.
class MedialIndex {
 public:
  MedialIndex(const BitVolume& centres, const std::vector<Medial>& medial) : centres_(centres) {
    const glm::i64vec3 d = centres.grid().dims;
    ny_ = d.y;
    by_rank_.resize(medial.size());
    for (std::uint32_t i = 0; i < by_rank_.size(); ++i) by_rank_[i] = i;
    std::sort(by_rank_.begin(), by_rank_.end(),
              [&](std::uint32_t a, std::uint32_t b) { return medial[a].ball.index < medial[b].ball.index; });
    before_row_.assign(static_cast<std::size_t>(d.y * d.z) + 1, 0);
    for (std::int64_t r = 0; r < d.y * d.z; ++r) {
      const std::uint64_t* row = centres.row(r % d.y, r / d.y);
      std::uint32_t n = 0;
      for (std::int64_t w = 0; w < centres.row_words(); ++w) n += static_cast<std::uint32_t>(std::popcount(row[w]));
      before_row_[static_cast<std::size_t>(r) + 1] = before_row_[static_cast<std::size_t>(r)] + n;
    }
  }
  // The record of the medial voxel c.
  std::uint32_t at(const glm::i64vec3& c) const {
    const std::uint64_t* row = centres_.row(c.y, c.z);
    std::uint32_t rank = before_row_[static_cast<std::size_t>(c.y + ny_ * c.z)];
    for (std::int64_t w = 0; w < (c.x >> 6); ++w) rank += static_cast<std::uint32_t>(std::popcount(row[w]));
    if (c.x & 63) rank += static_cast<std::uint32_t>(std::popcount(row[c.x >> 6] & ((std::uint64_t{1} << (c.x & 63)) - 1)));
    return by_rank_[rank];
  }

 private:
  const BitVolume& centres_;
  std::int64_t ny_ = 0;
  std::vector<std::uint32_t> by_rank_, before_row_;
};

// Each medial voxel's thickness becomes the mean over the medial voxels of
// its wall within three voxels of it (those whose thickness is within a
// voxel of its own). A single pair's thickness comes from two surface fits
// on a voxelized face, within about half a voxel; the mean over its
// neighbourhood on the medial sheet is within a fraction of that, and on a
// tapering wall (thickness linear along the sheet) it is still the
// thickness at the voxel. On a wall along the grid every pair whose fits
// see only its flat face reads the same, and so does the mean.
void smooth_medial_values(const BitVolume& centres, std::vector<Medial>& medial, const MedialIndex& index,
                          int threads) {
  const glm::i64vec3 d = centres.grid().dims;
  std::vector<float> smoothed(medial.size());
  const auto n = static_cast<std::int64_t>(medial.size());
  parallel_for(0, n, std::max<std::int64_t>(1, n / (threads * 16)), threads, [&](std::int64_t a, std::int64_t b) {
    constexpr std::int64_t R = 3;
    for (std::int64_t r = a; r < b; ++r) {
      const Medial& m = medial[static_cast<std::size_t>(r)];
      const auto idx = static_cast<std::int64_t>(m.ball.index);
      const glm::i64vec3 c{idx % d.x, (idx / d.x) % d.y, idx / (d.x * d.y)};
      double sum = 0.0;
      int count = 0;
      for (std::int64_t z = std::max<std::int64_t>(0, c.z - R); z <= std::min(d.z - 1, c.z + R); ++z)
        for (std::int64_t y = std::max<std::int64_t>(0, c.y - R); y <= std::min(d.y - 1, c.y + R); ++y)
          for (std::int64_t x = std::max<std::int64_t>(0, c.x - R); x <= std::min(d.x - 1, c.x + R); ++x) {
            const glm::i64vec3 q{x, y, z};
            if (norm2(q - c) > R * R || !centres.get(x, y, z)) continue;
            const Medial& other = medial[index.at(q)];
            const float v = other.ball.value;
            if (std::abs(v - m.ball.value) > 1.0f) continue;
            sum += v;
            ++count;
          }
      smoothed[static_cast<std::size_t>(r)] = static_cast<float>(sum / count);
    }
  });
  for (std::size_t i = 0; i < medial.size(); ++i) medial[i].ball.value = smoothed[i];
}

// Which pairs of face neighbours (p, p + e_axis) may see a wall between
// them: both filled, with other nearest empty voxels, and the directions to
// those not alike (u.w <= 0, medial_voxels' first test). The test reads the
// pair the same from either end, so each pair is tested once, from p; bit p
// of pairs[axis] is set when it passes. Nearly every filled voxel passes no
// test (inside a wall, neighbours' nearest empty voxels lie on one side),
// so this pass, half the reads of testing all six neighbours of every voxel
// and each site decoded once along a row, is most of finding medial voxels.
// It also stores each filled voxel's depth in `depths` (store_depths: the
// site it decodes anyway gives it).
std::array<BitVolume, 3> opposed_pairs(const BitVolume& solid, const DenseVolume<std::uint32_t>& nearest,
                                       DenseVolume<float>& depths, int threads, const detail::ProgressSpan& progress) {
  const Grid& grid = solid.grid();
  const glm::i64vec3 d = grid.dims;
  const PaddedIndex padded(grid);
  std::array<BitVolume, 3> pairs{BitVolume(grid), BitVolume(grid), BitVolume(grid)};
  const std::uint32_t* sites = nearest.values().data();
  const std::int64_t grain = std::max<std::int64_t>(1, d.z / (static_cast<std::int64_t>(threads) * 8));
  parallel_for(0, d.z, grain, threads, [&](std::int64_t k0, std::int64_t k1) {
    for (std::int64_t k = k0; k < k1; ++k) {
      progress.check_cancelled();
      for (std::int64_t j = 0; j < d.y; ++j) {
        const std::uint32_t* row_sites = sites + static_cast<std::size_t>(d.x * (j + d.y * k));
        // The neighbours above in y and z: their filled bits and sites (null
        // outside the grid).
        const std::uint64_t* up_rows[2] = {j + 1 < d.y ? solid.row(j + 1, k) : nullptr,
                                           k + 1 < d.z ? solid.row(j, k + 1) : nullptr};
        const std::uint32_t* up_sites[2] = {row_sites + d.x, row_sites + d.x * d.y};
        std::uint64_t* out[3] = {pairs[0].row(j, k), pairs[1].row(j, k), pairs[2].row(j, k)};
        float* depth_row = depths.slab(k) + j * d.x;
        detail::for_each_row_run(solid.row(j, k), solid.row_words(), d.x, false, [&](std::int64_t a, std::int64_t b) {
          std::uint32_t fp_index = row_sites[a];
          glm::i64vec3 fp = padded.at(fp_index);
          for (std::int64_t i = a; i < b; ++i) {
            const glm::i64vec3 p{i, j, k};
            const glm::i64vec3 u = fp - p;
            depth_row[i] = -static_cast<float>(norm2(u));
            const std::uint64_t bit = std::uint64_t{1} << (i & 63);
            // Along x the next voxel's site is the next voxel's own: decoded once.
            std::uint32_t next_index = fp_index;
            glm::i64vec3 next = fp;
            if (i + 1 < b) {
              next_index = row_sites[i + 1];
              if (next_index != fp_index) {
                next = padded.at(next_index);
                const glm::i64vec3 w = next - glm::i64vec3{i + 1, j, k};
                if (u.x * w.x + u.y * w.y + u.z * w.z <= 0) out[0][i >> 6] |= bit;
              }
            }
            for (int axis = 1; axis < 3; ++axis) {
              const std::uint64_t* q_row = up_rows[axis - 1];
              if (!q_row || !((q_row[i >> 6] >> (i & 63)) & 1u)) continue;
              const std::uint32_t fq_index = up_sites[axis - 1][i];
              if (fq_index == fp_index) continue;
              glm::i64vec3 q = p;
              q[axis] += 1;
              const glm::i64vec3 w = padded.at(fq_index) - q;
              if (u.x * w.x + u.y * w.y + u.z * w.z <= 0) out[axis][i >> 6] |= bit;
            }
            fp_index = next_index;
            fp = next;
          }
        });
      }
    }
  });
  return pairs;
}

// The filled voxels of row (j, k) that medial_voxels must look at, a word
// at a time: those in a pair that passed opposed_pairs' test, and those
// with both neighbours along an axis empty (a wall one voxel thick).
struct MedialCandidates {
  const BitVolume& solid;
  const std::array<BitVolume, 3>& pairs;
  std::uint64_t word(std::int64_t j, std::int64_t k, std::int64_t w) const {
    const glm::i64vec3 d = solid.grid().dims;
    const std::int64_t last = solid.row_words() - 1;
    auto at = [&](const BitVolume& v, std::int64_t y, std::int64_t z, bool inside) {
      return inside ? v.row(y, z)[w] : std::uint64_t{0};
    };
    const std::uint64_t* row = solid.row(j, k);
    const std::uint64_t* px = pairs[0].row(j, k);
    // Bit i of a row's neighbour at i - 1 and i + 1, across words.
    const std::uint64_t left = row[w] << 1 | (w > 0 ? row[w - 1] >> 63 : 0);
    const std::uint64_t right = row[w] >> 1 | (w < last ? row[w + 1] << 63 : 0);
    const std::uint64_t pair_below_x = px[w] << 1 | (w > 0 ? px[w - 1] >> 63 : 0);
    const std::uint64_t thin_x = ~left & ~right;
    const std::uint64_t thin_y = ~at(solid, j - 1, k, j > 0) & ~at(solid, j + 1, k, j + 1 < d.y);
    const std::uint64_t thin_z = ~at(solid, j, k - 1, k > 0) & ~at(solid, j, k + 1, k + 1 < d.z);
    return row[w] & (px[w] | pair_below_x | pairs[1].row(j, k)[w] | at(pairs[1], j - 1, k, j > 0) |
                     pairs[2].row(j, k)[w] | at(pairs[2], j, k - 1, k > 0) | thin_x | thin_y | thin_z);
  }
};

// The medial voxels: each with its ball (its own distance to the surface)
// and the wall's thickness there (the mean over the pairs it is part of).
// Also marks them in `centres`, and stores every filled voxel's depth in
// `depths` (as `out` holds them, below).
std::vector<Medial> medial_voxels(const BitVolume& solid, const DenseVolume<std::uint32_t>& nearest,
                                  DenseVolume<float>& depths, BitVolume& centres, int threads,
                                  const detail::ProgressSpan& progress) {
  const Grid& grid = solid.grid();
  const glm::i64vec3 d = grid.dims;
  const PaddedIndex padded(grid);
  const double cos_separation = std::cos(kWallSeparationDegrees * 3.14159265358979323846 / 180.0);
  const std::array<BitVolume, 3> pairs = opposed_pairs(solid, nearest, depths, threads, progress.part(0.0, 0.8));
  const MedialCandidates candidates{solid, pairs};
  std::mutex mutex;
  std::vector<Medial> balls;
  const std::int64_t grain = std::max<std::int64_t>(1, d.z / (static_cast<std::int64_t>(threads) * 8));
  parallel_for(0, d.z, grain, threads, [&](std::int64_t k0, std::int64_t k1) {
    std::vector<Medial> found;
    FitCache fits(solid);
    // A voxel's six neighbours: their offsets in `nearest`, and the bit rows
    // that say whether they are filled (null outside the grid).
    const std::uint32_t* sites = nearest.values().data();
    const std::int64_t stride[3] = {1, d.x, d.x * d.y};
    for (std::int64_t k = k0; k < k1; ++k) {
      progress.check_cancelled();
      for (std::int64_t j = 0; j < d.y; ++j) {
        const std::uint64_t* rows[3][2] = {
            {solid.row(j, k), solid.row(j, k)},
            {j > 0 ? solid.row(j - 1, k) : nullptr, j + 1 < d.y ? solid.row(j + 1, k) : nullptr},
            {k > 0 ? solid.row(j, k - 1) : nullptr, k + 1 < d.z ? solid.row(j, k + 1) : nullptr}};
        const std::uint32_t* row_sites = sites + static_cast<std::size_t>(d.x * (j + d.y * k));
        for (std::int64_t w = 0; w < solid.row_words(); ++w)
          for (std::uint64_t bits = candidates.word(j, k, w); bits; bits &= bits - 1) {
            const std::int64_t i = w * 64 + std::countr_zero(bits);
            const glm::i64vec3 p{i, j, k};
            const std::uint32_t fp_index = row_sites[i];
            const glm::i64vec3 fp = padded.at(fp_index);
            const glm::i64vec3 u = fp - p;
            const std::int64_t u2 = norm2(u);
            double sum = 0.0;
            int count = 0;
            Chord chord;
            auto add = [&](const glm::i64vec3& q, const glm::i64vec3& f1, const glm::i64vec3& f2) {
              const double t = wall_between(fits, p, q, f1, f2, cos_separation);
              if (t < 0) return;
              sum += t;
              ++count;
              chord = {glm::i32vec3(f1), glm::i32vec3(f2)};
            };
            for (int axis = 0; axis < 3; ++axis) {
              bool empty_both = true;
              for (int side = -1; side <= 1; side += 2) {
                // Neighbour q's row of bits, and its x (along x, this row).
                const std::uint64_t* q_row = rows[axis][side > 0];
                const std::int64_t qx = axis == 0 ? i + side : i;
                if (!q_row || qx < 0 || qx >= d.x || !((q_row[qx >> 6] >> (qx & 63)) & 1u)) continue;
                empty_both = false;
                const std::uint32_t fq_index = row_sites[i + side * stride[axis]];
                if (fq_index == fp_index) continue;
                glm::i64vec3 q = p;
                q[axis] += side;
                const glm::i64vec3 fq = padded.at(fq_index);
                const glm::i64vec3 w = fq - q;
                // Cheap first test on the directions to the two voxels.
                if (u.x * w.x + u.y * w.y + u.z * w.z > 0) continue;
                add(q, fp, fq);
              }
              if (empty_both) {
                glm::i64vec3 lo = p, hi = p;
                lo[axis] -= 1;
                hi[axis] += 1;
                add(p, lo, hi);
              }
            }
            if (count == 0) continue;
            found.push_back({{static_cast<std::uint64_t>(i + d.x * (j + d.y * k)), static_cast<std::uint32_t>(u2),
                              static_cast<float>(sum / count)},
                             chord, u2 + 2 * detail::ceil_sqrt(u2) + 1});
          }
      }
    }
    // This piece's layers are its own, in `centres` too (rows share no words).
    for (const Medial& m : found) {
      const auto index = static_cast<std::int64_t>(m.ball.index);
      centres.set(index % d.x, (index / d.x) % d.y, index / (d.x * d.y), true);
    }
    std::lock_guard lock(mutex);
    balls.insert(balls.end(), found.begin(), found.end());
  });
  // Largest first; equal radii in memory order, so the result does not
  // depend on the thread count.
  std::sort(balls.begin(), balls.end(), [](const Medial& a, const Medial& b) {
    return a.ball.r2 != b.ball.r2 ? a.ball.r2 > b.ball.r2 : a.ball.index < b.ball.index;
  });
  return balls;
}

// Until a filled voxel has its wall, `out` holds minus its squared depth
// (the squared distance to its nearest empty voxel, at least 1), so the
// feature transform's memory can be reused for the nearest medial voxels
// while the depths stay at hand. Walls are at least half a voxel thick, so
// a negative value is a voxel still to paint. opposed_pairs stores them,
// from the nearest empty voxels it decodes anyway.
inline std::int64_t depth2_of(const DenseVolume<float>& out, std::int64_t x, std::int64_t y, std::int64_t z) {
  return static_cast<std::int64_t>(-out.at(x, y, z));
}

// Nearest voxel of a point no further than a few voxels outside the grid
// (truncation of a positive number is its floor).
inline glm::i64vec3 rounded(const glm::dvec3& p) {
  constexpr double kBias = 1024.0;
  return {static_cast<std::int64_t>(p.x + 0.5 + kBias) - 1024, static_cast<std::int64_t>(p.y + 0.5 + kBias) - 1024,
          static_cast<std::int64_t>(p.z + 0.5 + kBias) - 1024};
}

// Each filled voxel takes the wall of its nearest medial voxel (`nearest`
// holds the nearest medial voxels now), when it lies in that wall: no
// deeper than the wall's ball and a voxel (a deeper voxel belongs to a
// thicker wall: under a rib's root), between the wall's two faces (its
// projection on the chord within a voxel and a half of the chord), and
// with the wall's faces on both sides of it (the chord moved to it, across
// the wall, ends outside the solid, or within two voxels further out: at a
// rib's root the moved chord ends inside the wall the rib stands on). The
// nearest medial point is the foot of the voxel's own cross-section of the
// wall, so a tapering wall reads its thickness where the voxel is, and the
// ends and edges of a wall take the wall they end. Returns the filled
// voxels this leaves (junctions of walls), for the balls.
BitVolume paint_nearest_walls(const BitVolume& solid, const DenseVolume<std::uint32_t>& nearest,
                              const std::vector<Medial>& medial, const MedialIndex& index, DenseVolume<float>& out,
                              int threads, const detail::ProgressSpan& progress) {
  const Grid& grid = solid.grid();
  const glm::i64vec3 d = grid.dims;
  const PaddedIndex padded(grid);
  auto filled = [&](const glm::i64vec3& p) { return filled_at(solid, p); };
  // Whether the face at `end` of the chord, moved across the wall, is
  // still there: the moved end, or a voxel or two further out along
  // `out_dir`, is outside the solid (the voxel lattice puts a face's empty
  // voxels anywhere within a voxel of it).
  auto face_at = [&](const glm::dvec3& end, const glm::dvec3& out_dir) {
    for (int t = 0; t <= 2; ++t)
      if (!filled(rounded(end + out_dir * static_cast<double>(t)))) return true;
    return false;
  };
  BitVolume left = solid.clone();
  const std::int64_t grain = std::max<std::int64_t>(1, d.z / (static_cast<std::int64_t>(threads) * 8));
  parallel_for(0, d.z, grain, threads, [&](std::int64_t k0, std::int64_t k1) {
    for (std::int64_t k = k0; k < k1; ++k) {
      progress.check_cancelled();
      for (std::int64_t j = 0; j < d.y; ++j) {
        float* out_row = out.slab(k) + j * d.x;
        std::uint64_t* left_row = left.row(j, k);
        // Neighbours along a row mostly share their nearest medial voxel.
        std::uint32_t last_site = detail::kNoNearestVoxel;
        const Medial* m = nullptr;
        glm::i64vec3 c{0}, from{0}, span{0};
        glm::dvec3 unit{0.0};
        double length = 0.0, length2 = 0.0;
        detail::for_each_row_run(solid.row(j, k), solid.row_words(), d.x, false, [&](std::int64_t a, std::int64_t b) {
          for (std::int64_t i = a; i < b; ++i) {
            const std::uint32_t site = nearest.at(i, j, k);
            if (site == detail::kNoNearestVoxel) continue;
            if (site != last_site) {
              last_site = site;
              c = padded.at(site);
              m = &medial[index.at(c)];
              from = glm::i64vec3(m->chord.from);
              span = glm::i64vec3(m->chord.to) - from;
              length2 = static_cast<double>(norm2(span));
              length = std::sqrt(length2);
              unit = glm::dvec3(span) / length;
            }
            const glm::i64vec3 v{i, j, k};
            if (c != v) {
              if (static_cast<std::int64_t>(-out_row[i]) >= m->reach2) continue;
              const glm::i64vec3 rel = v - from;
              const auto along = static_cast<double>(rel.x * span.x + rel.y * span.y + rel.z * span.z);
              if (along < -1.5 * length || along > length2 + 1.5 * length) continue;
              const glm::dvec3 shift = glm::dvec3(rel) - glm::dvec3(span) * (along / length2);
              if (!face_at(glm::dvec3(from) + shift, -unit) || !face_at(glm::dvec3(from + span) + shift, unit)) continue;
            }
            out_row[i] = m->ball.value;
            left_row[i >> 6] &= ~(std::uint64_t{1} << (i & 63));
          }
        });
      }
    }
  });
  return left;
}

// The voxels of `candidates` nothing else reached (still negative in `out`)
// take, layer by layer outwards from the painted ones, the largest value
// among their 26 neighbours of the layers before. A piece with no medial
// voxel at all (a fragment with no two surfaces facing each other) keeps its
// own ball's diameter less one voxel.
void fill_unreached(const BitVolume& candidates, DenseVolume<float>& out) {
  const glm::i64vec3 d = candidates.grid().dims;
  std::vector<std::int64_t> left;
  for (std::int64_t k = 0; k < d.z; ++k)
    for (std::int64_t j = 0; j < d.y; ++j)
      detail::for_each_row_run(candidates.row(j, k), candidates.row_words(), d.x, false,
                               [&](std::int64_t a, std::int64_t b) {
                                 const float* row = out.slab(k) + j * d.x;
                                 for (std::int64_t i = a; i < b; ++i)
                                   if (row[i] < 0.0f) left.push_back(i + d.x * (j + d.y * k));
                               });
  std::vector<std::pair<std::int64_t, float>> layer;
  while (!left.empty()) {
    layer.clear();
    std::vector<std::int64_t> still;
    for (std::int64_t index : left) {
      const std::int64_t x = index % d.x, y = (index / d.x) % d.y, z = index / (d.x * d.y);
      float best = 0.0f;  // unpainted neighbours hold negative depths
      for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const std::int64_t i = x + dx, j = y + dy, k = z + dz;
            if (i < 0 || j < 0 || k < 0 || i >= d.x || j >= d.y || k >= d.z) continue;
            best = std::max(best, out.at(i, j, k));
          }
      if (best > 0.0f) {
        layer.emplace_back(index, best);
      } else {
        still.push_back(index);
      }
    }
    if (layer.empty()) {
      for (std::int64_t index : still) {
        float& value = out.values()[static_cast<std::size_t>(index)];
        value = static_cast<float>(std::max(1.0, 2.0 * std::sqrt(static_cast<double>(-value)) - 1.0));
      }
      break;
    }
    for (const auto& [index, value] : layer) out.values()[static_cast<std::size_t>(index)] = value;
    left.swap(still);
  }
}

}  // namespace

DenseVolume<float> wall_thickness(const BitVolume& solid, int threads, JobControl* control) {
  const Grid& grid = solid.grid();
  const int nthreads = threads > 0 ? threads : default_thread_count();
  const detail::ProgressSpan progress{control, 0.0, 1.0};
  DenseVolume<float> out(grid, 0.0f);
  if (grid.voxel_count() == 0) return out;
  DenseVolume<std::uint32_t> nearest = detail::nearest_empty_voxels(solid, nthreads, control, 0.0, 0.3);
  BitVolume centres(grid);
  // Also stores the depths in `out` (see store_depths).
  std::vector<Medial> medial = medial_voxels(solid, nearest, out, centres, nthreads, progress.part(0.3, 0.45));
  const MedialIndex index(centres, medial);
  smooth_medial_values(centres, medial, index, nthreads);
  detail::nearest_marked_voxels(centres, nearest, &solid, nthreads, control, 0.45, 0.65);
  const BitVolume left = paint_nearest_walls(solid, nearest, medial, index, out, nthreads, progress.part(0.65, 0.75));
  nearest = {};
  // The junctions of walls (a rib's root in the wall it stands on), where
  // no wall's nearest medial voxel took them: the balls of the walls,
  // largest first, so the thickest wall a voxel is part of owns it.
  const glm::i64vec3 d = grid.dims;
  std::size_t next = 0;
  const detail::BallSource source = [&](Ball& ball) {
    if (next == medial.size()) return false;
    ball = medial[next].ball;
    ball.tag = static_cast<std::uint32_t>(next++);
    return true;
  };
  const detail::BallContained contained = [&](std::int64_t x, std::int64_t y, std::int64_t z, std::int64_t r2) {
    return detail::inside_a_neighbour(d, x, y, z, r2, [&](std::int64_t i, std::int64_t j, std::int64_t k) {
      if (!centres.get(i, j, k)) return std::int64_t{0};
      return static_cast<std::int64_t>(medial[index.at({i, j, k})].ball.r2);
    });
  };
  // A wall's ball paints only the voxels between the wall's two faces:
  // those whose projection on its chord lies between the chord's ends.
  // Where a thin rib stands on a thick wall near the wall's end face, the
  // wall's balls do not reach the wall's edge voxels beside the rib's root,
  // and the rib's balls (or its edge voxels, filled from their neighbours)
  // would give them the rib's value; they lie outside the rib's faces.
  const detail::BallAccepts between_faces = [&](const Ball& ball, std::int64_t x, std::int64_t y, std::int64_t z) {
    const Chord& chord = medial[ball.tag].chord;
    const glm::i64vec3 from(chord.from), span = glm::i64vec3(chord.to) - from;
    const glm::i64vec3 v = glm::i64vec3{x, y, z} - from;
    const std::int64_t along = v.x * span.x + v.y * span.y + v.z * span.z;
    return along >= 0 && along <= norm2(span);
  };
  // And only voxels nearer the surface than the ball's radius (medial
  // voxels have their wall already): within a wall, only its medial voxels
  // are as deep as its balls are wide. A voxel as deep or deeper belongs to
  // a thicker wall whose balls missed it (under a rib's root, near the end
  // face of the wall it stands on). The wall's own voxels this misses on
  // the lattice are painted by the grown balls below, with the same values.
  const detail::BallAccepts in_the_wall = [&](const Ball& ball, std::int64_t x, std::int64_t y, std::int64_t z) {
    return depth2_of(out, x, y, z) < static_cast<std::int64_t>(ball.r2) && between_faces(ball, x, y, z);
  };
  detail::paint_balls_largest_first(left, out, source, contained, {}, nthreads, progress.part(0.75, 0.85), in_the_wall);
  // The edges and corners of walls at their junctions, which no medial
  // ball reaches: the ball at a wall's end is r from the end face, and the
  // edge's corner lies up to sqrt(3) r from it (a cube's corner). Each such
  // voxel takes the largest wall whose ball, grown by sqrt(3) and a voxel,
  // reaches it and whose faces it lies between. These voxels are few, so
  // the engine goes straight to its sparse phase.
  // Found layer by layer on every thread: a pass over every voxel the
  // walls left, 10 ms at 512^3 that 16 threads would wait for on one.
  BitVolume edges(grid);
  std::atomic<std::int64_t> edge_voxels{0};
  const auto find_edges = [&](std::int64_t k0, std::int64_t k1) {
    std::int64_t found = 0;
    for (std::int64_t k = k0; k < k1; ++k)
      for (std::int64_t j = 0; j < d.y; ++j) {
        const float* row = out.slab(k) + j * d.x;
        detail::for_each_row_run(left.row(j, k), left.row_words(), d.x, false, [&](std::int64_t a, std::int64_t b) {
          for (std::int64_t i = a; i < b; ++i)
            if (row[i] < 0.0f) {
              edges.set(i, j, k, true);  // this piece's layers: rows share no words
              ++found;
            }
        });
      }
    edge_voxels += found;
  };
  parallel_for(0, d.z, std::max<std::int64_t>(1, d.z / (static_cast<std::int64_t>(nthreads) * 8)), nthreads,
               find_edges);
  if (edge_voxels > 0) {
    next = 0;
    const detail::BallSource grown = [&](Ball& ball) {
      if (!source(ball)) return false;
      const auto r2 = static_cast<std::int64_t>(ball.r2);
      ball.r2 = static_cast<std::uint32_t>(std::min<std::int64_t>(3 * r2 + 2 * detail::ceil_sqrt(3 * r2) + 1, UINT32_MAX));
      return true;
    };
    detail::BallPaintingTuning sparse_only;
    sparse_only.sparse_from = INT64_MAX;
    detail::paint_balls_largest_first(
        edges, out, grown, [](std::int64_t, std::int64_t, std::int64_t, std::int64_t) { return false; }, sparse_only,
        nthreads, progress.part(0.85, 0.95), between_faces);
  }
  // What is still unpainted lies among the edges (the balls paint only
  // positive values), a small share of what the walls left.
  fill_unreached(edges, out);
  progress.report(1.0);
  return out;
}

ThicknessErrorBound wall_thickness_error_bound() { return {1.0, 1.0}; }

std::string wall_thickness_error_statement(double voxel_size) {
  return "within " + voxels_and_model_units(wall_thickness_error_bound(), voxel_size) +
         " of the distance between the wall's two faces: the voxelization places each face anywhere within a "
         "voxel; a wall along the grid axes N voxels thick reports exactly N where its faces are flat for two "
         "voxels around";
}

}  // namespace voxd
