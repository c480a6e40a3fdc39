// Wall thickness (voxd/analysis/wall_thickness.h): medial pairs from the
// feature transform, their balls painted largest first, and the voxels no
// medial ball reaches filled from their neighbours.
#include "voxd/analysis/wall_thickness.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <vector>

#include "analysis/ball_painting.h"
#include "analysis/progress_span.h"
#include "analysis/row_runs.h"
#include "voxd/detail/nearest_empty.h"
#include "voxd/parallel.h"

namespace voxd {
namespace {

using detail::Ball;
using detail::PaddedIndex;

inline std::int64_t norm2(const glm::i64vec3& v) { return v.x * v.x + v.y * v.y + v.z * v.z; }

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

SurfaceFit fit_surface(const BitVolume& solid, const glm::i64vec3& f) {
  const glm::i64vec3 d = solid.grid().dims;
  auto filled = [&](const glm::i64vec3& p) {
    return p.x >= 0 && p.y >= 0 && p.z >= 0 && p.x < d.x && p.y < d.y && p.z < d.z && solid.get(p.x, p.y, p.z);
  };
  SurfaceFit fit;
  glm::dvec3 g{0.0};
  for (int z = -2; z <= 2; ++z)
    for (int y = -2; y <= 2; ++y)
      for (int x = -2; x <= 2; ++x) {
        const int r2 = x * x + y * y + z * z;
        if (r2 == 0 || r2 > 4 || !filled(f + glm::i64vec3{x, y, z})) continue;
        g += glm::dvec3(x, y, z) / std::sqrt(static_cast<double>(r2));
      }
  const double len = std::sqrt(g.x * g.x + g.y * g.y + g.z * g.z);
  if (len < 1e-9) return fit;
  fit.normal = g / len;
  double projections[125];
  int n = 0, k = 0;
  for (int z = -2; z <= 2; ++z)
    for (int y = -2; y <= 2; ++y)
      for (int x = -2; x <= 2; ++x) {
        const glm::dvec3 o(x, y, z);
        const double along = o.x * fit.normal.x + o.y * fit.normal.y + o.z * fit.normal.z;
        const glm::dvec3 across = o - along * fit.normal;
        if (std::abs(along) > 1.5 || across.x * across.x + across.y * across.y + across.z * across.z > 4.0) continue;
        projections[n++] = along;
        k += filled(f + glm::i64vec3{x, y, z}) ? 1 : 0;
      }
  if (k > 0 && k < n) {
    std::nth_element(projections, projections + (n - k), projections + n);
    const double lowest_filled = projections[n - k];
    const double highest_empty = *std::max_element(projections, projections + (n - k));
    fit.offset = 0.5 * (lowest_filled + highest_empty);
  }
  fit.valid = true;
  return fit;
}

// The wall between the empty voxels fp and fq on its two sides, seen from
// the medial voxels p and q (p == q for a wall one voxel thick): its
// thickness in voxels if the two surfaces face each other, else a negative
// value. Facing: the fitted surface normals are at least the separation
// angle apart; or, where a surface has no normal of its own (a concave
// edge, where a rib meets a wall), the directions from p and q to fp and fq
// are, if both are at least two voxels long (shorter ones are the lattice's
// steps on a convex edge, not a direction).
double wall_between(const BitVolume& solid, const glm::i64vec3& p, const glm::i64vec3& q, const glm::i64vec3& fp,
                    const glm::i64vec3& fq, double cos_separation) {
  const SurfaceFit a = fit_surface(solid, fp), b = fit_surface(solid, fq);
  if (a.valid && b.valid &&
      a.normal.x * b.normal.x + a.normal.y * b.normal.y + a.normal.z * b.normal.z <= cos_separation) {
    glm::dvec3 n = a.normal - b.normal;
    n /= std::sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
    const glm::dvec3 span(fq - fp);
    const double across = span.x * n.x + span.y * n.y + span.z * n.z;
    return std::max(0.5, across - a.offset - b.offset);
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
// (padded indices).
struct Chord {
  std::uint32_t from = 0, to = 0;
};

struct Medial {
  Ball ball;
  Chord chord;
};

// The medial voxels: each with its ball (its own distance to the surface)
// and the wall's thickness there (the mean over the pairs it is part of).
// Also marks them in `centres`.
std::vector<Medial> medial_voxels(const BitVolume& solid, const DenseVolume<std::uint32_t>& nearest,
                                  BitVolume& centres, int threads, const detail::ProgressSpan& progress) {
  const Grid& grid = solid.grid();
  const glm::i64vec3 d = grid.dims;
  const PaddedIndex padded(grid);
  const double cos_separation = std::cos(kWallSeparationDegrees * 3.14159265358979323846 / 180.0);
  std::mutex mutex;
  std::vector<Medial> balls;
  const std::int64_t grain = std::max<std::int64_t>(1, d.z / (static_cast<std::int64_t>(threads) * 8));
  parallel_for(0, d.z, grain, threads, [&](std::int64_t k0, std::int64_t k1) {
    std::vector<Medial> found;
    for (std::int64_t k = k0; k < k1; ++k) {
      progress.check_cancelled();
      for (std::int64_t j = 0; j < d.y; ++j) {
        detail::for_each_row_run(solid.row(j, k), solid.row_words(), d.x, false, [&](std::int64_t a, std::int64_t b) {
          for (std::int64_t i = a; i < b; ++i) {
            const glm::i64vec3 p{i, j, k};
            const std::uint32_t fp_index = nearest.at(i, j, k);
            const glm::i64vec3 fp = padded.at(fp_index);
            const glm::i64vec3 u = fp - p;
            const std::int64_t u2 = norm2(u);
            double sum = 0.0;
            int count = 0;
            Chord chord;
            auto add = [&](const glm::i64vec3& q, const glm::i64vec3& f1, const glm::i64vec3& f2) {
              const double t = wall_between(solid, p, q, f1, f2, cos_separation);
              if (t < 0) return;
              sum += t;
              ++count;
              chord = {padded.of(f1.x, f1.y, f1.z), padded.of(f2.x, f2.y, f2.z)};
            };
            for (int axis = 0; axis < 3; ++axis) {
              bool empty_both = true;
              for (int side = -1; side <= 1; side += 2) {
                glm::i64vec3 q = p;
                q[axis] += side;
                if (q[axis] < 0 || q[axis] >= d[axis] || !solid.get(q.x, q.y, q.z)) continue;
                empty_both = false;
                const std::uint32_t fq_index = nearest.at(q.x, q.y, q.z);
                if (fq_index == fp_index) continue;
                const glm::i64vec3 fq = padded.at(fq_index);
                const glm::i64vec3 w = fq - q;
                // Cheap first test on the directions to the two voxels.
                const auto dot = static_cast<double>(u.x * w.x + u.y * w.y + u.z * w.z);
                if (dot > 0.0) continue;
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
                             chord});
          }
        });
      }
    }
    std::lock_guard lock(mutex);
    balls.insert(balls.end(), found.begin(), found.end());
  });
  for (const Medial& m : balls) {
    const auto index = static_cast<std::int64_t>(m.ball.index);
    centres.set(index % d.x, (index / d.x) % d.y, index / (d.x * d.y), true);
  }
  // Largest first; equal radii in memory order, so the result does not
  // depend on the thread count.
  std::sort(balls.begin(), balls.end(), [](const Medial& a, const Medial& b) {
    return a.ball.r2 != b.ball.r2 ? a.ball.r2 > b.ball.r2 : a.ball.index < b.ball.index;
  });
  return balls;
}

// Each medial voxel's value along its chord, the segment across the wall
// through it: a voxel takes the thickness of its own cross-section of the
// wall. Balls alone would give a voxel of a tapering wall the value of a
// thicker section nearby (a ball reaches half its diameter along the wall),
// which moves where a thin region starts by half the threshold. Largest
// ball first, the first chord to reach a voxel sets it. Returns the filled
// voxels no chord reached, left to the balls: the sides of curved walls
// between chords, the ends and edges of walls. On a flat wall the chords
// cover nearly all of it, and its balls, the costliest part to paint (a
// plate T voxels thick has T^2 rows per ball), have little left to do.
BitVolume paint_chords(const BitVolume& solid, const std::vector<Medial>& medial, DenseVolume<float>& out) {
  const glm::i64vec3 d = solid.grid().dims;
  const PaddedIndex padded(solid.grid());
  BitVolume left = solid.clone();
  for (const Medial& m : medial) {
    const glm::dvec3 a(padded.at(m.chord.from)), b(padded.at(m.chord.to));
    const glm::dvec3 span = b - a;
    const double length = std::sqrt(span.x * span.x + span.y * span.y + span.z * span.z);
    const int steps = static_cast<int>(std::ceil(length * 4.0));
    for (int s = 1; s < steps; ++s) {
      const glm::dvec3 at = a + span * (static_cast<double>(s) / steps);
      const auto i = static_cast<std::int64_t>(std::lround(at.x)), j = static_cast<std::int64_t>(std::lround(at.y)),
                 k = static_cast<std::int64_t>(std::lround(at.z));
      if (i < 0 || j < 0 || k < 0 || i >= d.x || j >= d.y || k >= d.z) continue;
      if (!left.get(i, j, k)) continue;
      left.set(i, j, k, false);
      out.at(i, j, k) = m.ball.value;
    }
  }
  return left;
}

// The filled voxels no medial ball reached take, layer by layer outwards
// from the painted ones, the largest value among their 26 neighbours of the
// layers before. A piece with no medial voxel at all (a fragment with no two
// surfaces facing each other) keeps its own ball's diameter less one voxel.
void fill_unreached(const BitVolume& solid, const DenseVolume<std::uint32_t>& nearest, DenseVolume<float>& out) {
  const glm::i64vec3 d = solid.grid().dims;
  std::vector<std::int64_t> left;
  // Voxels no ball and no chord reached keep 0 until filled here.
  for (std::int64_t k = 0; k < d.z; ++k)
    for (std::int64_t j = 0; j < d.y; ++j)
      detail::for_each_row_run(solid.row(j, k), solid.row_words(), d.x, false, [&](std::int64_t a, std::int64_t b) {
        const float* row = out.slab(k) + j * d.x;
        for (std::int64_t i = a; i < b; ++i)
          if (row[i] == 0.0f) left.push_back(i + d.x * (j + d.y * k));
      });
  std::vector<std::pair<std::int64_t, float>> layer;
  while (!left.empty()) {
    layer.clear();
    std::vector<std::int64_t> still;
    for (std::int64_t index : left) {
      const std::int64_t x = index % d.x, y = (index / d.x) % d.y, z = index / (d.x * d.y);
      float best = 0.0f;
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
      const PaddedIndex padded(solid.grid());
      for (std::int64_t index : still) {
        const glm::i64vec3 p{index % d.x, (index / d.x) % d.y, index / (d.x * d.y)};
        const double r = std::sqrt(static_cast<double>(norm2(padded.at(nearest.values()[static_cast<std::size_t>(index)]) - p)));
        out.values()[static_cast<std::size_t>(index)] = static_cast<float>(std::max(1.0, 2.0 * r - 1.0));
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
  const DenseVolume<std::uint32_t> nearest = detail::nearest_empty_voxels(solid, nthreads, control, 0.0, 0.4);
  BitVolume centres(grid);
  const std::vector<Medial> medial = medial_voxels(solid, nearest, centres, nthreads, progress.part(0.4, 0.5));
  progress.report(0.5);
  const PaddedIndex padded(grid);
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
      return norm2(padded.at(nearest.at(i, j, k)) - glm::i64vec3{i, j, k});
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
    const glm::i64vec3 from = padded.at(chord.from);
    const glm::i64vec3 span = padded.at(chord.to) - from;
    const glm::i64vec3 v = glm::i64vec3{x, y, z} - from;
    const std::int64_t along = v.x * span.x + v.y * span.y + v.z * span.z;
    return along >= 0 && along <= norm2(span);
  };
  // And only voxels nearer the surface than the ball's radius, or medial
  // voxels themselves: within a wall, only its medial voxels are as deep
  // as its balls are wide. A voxel as deep or deeper belongs to a thicker
  // wall whose balls missed it (under a rib's root, near the end face of
  // the wall it stands on). The wall's own voxels this misses on the
  // lattice are painted by the grown balls below, with the same values.
  const detail::BallAccepts in_the_wall = [&](const Ball& ball, std::int64_t x, std::int64_t y, std::int64_t z) {
    return (centres.get(x, y, z) ||
            norm2(padded.at(nearest.at(x, y, z)) - glm::i64vec3{x, y, z}) < static_cast<std::int64_t>(ball.r2)) &&
           between_faces(ball, x, y, z);
  };
  // Chords first: a voxel on a chord takes the chord's value whatever
  // ball contains it, so the balls paint only what the chords left.
  const BitVolume off_chords = paint_chords(solid, medial, out);
  detail::paint_balls_largest_first(off_chords, out, source, contained, {}, nthreads, progress.part(0.5, 0.8),
                                    in_the_wall);
  // The edges and corners of walls, which no medial ball reaches: the ball
  // at a wall's end is r from the end face, and the edge's corner lies up
  // to sqrt(3) r from it (a cube's corner). Each such voxel takes the
  // largest wall whose ball, grown by sqrt(3) and a voxel, reaches it and
  // whose faces it lies between. These voxels are few, so the engine goes
  // straight to its sparse phase.
  BitVolume edges(grid);
  std::int64_t edge_voxels = 0;
  for (std::int64_t k = 0; k < d.z; ++k)
    for (std::int64_t j = 0; j < d.y; ++j)
      detail::for_each_row_run(solid.row(j, k), solid.row_words(), d.x, false, [&](std::int64_t a, std::int64_t b) {
        const float* row = out.slab(k) + j * d.x;
        for (std::int64_t i = a; i < b; ++i)
          if (row[i] == 0.0f) {
            edges.set(i, j, k, true);
            ++edge_voxels;
          }
      });
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
        nthreads, progress.part(0.8, 0.95), between_faces);
  }
  fill_unreached(solid, nearest, out);
  progress.report(1.0);
  return out;
}

WallThicknessErrorBound wall_thickness_error_bound() { return {}; }

std::string wall_thickness_error_statement(double voxel_size) {
  const WallThicknessErrorBound b = wall_thickness_error_bound();
  char text[512];
  std::snprintf(text, sizeof text,
                "within -%g to +%g voxels (-%g to +%g model units) of the distance between the wall's two faces: "
                "the voxelization places each face anywhere within a voxel; a wall along the grid axes N voxels "
                "thick reports exactly N",
                b.below_voxels, b.above_voxels, b.below_voxels * voxel_size, b.above_voxels * voxel_size);
  return text;
}

}  // namespace voxd
