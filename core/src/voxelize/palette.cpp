// Palette voxelization by Monte Carlo column rays. See voxd/voxelize/palette.h.
//
// Every voxel of a column shares the column's sample pattern (the rays'
// (y, z) and the points' x offsets within the voxel), so each element's
// membership of the pattern is a bit mask computed once per column, and a
// voxel's evaluation is a few popcounts per element: inside mask I against
// element mask E.
#include <algorithm>
#include <bit>
#include <cmath>
#include <vector>

#include "voxd/error.h"
#include "voxd/voxelize/palette.h"
#include "voxd/voxelize/palette_geometry.h"
#include "voxd/parallel.h"
#include "voxelize/fixed_point_mesh.h"
#include "voxelize/row_rays.h"
#include "voxelize/splitmix.h"

namespace voxd {
namespace {

using detail::kFixedOne;
using detail::RayCrossing;
using detail::splitmix_hash;
using detail::unit_interval;
using Word = std::uint64_t;

struct Choice {
  std::uint8_t element = 0;
  std::uint8_t similarity = 0;
};

// The first element of each kind the shortcut uses, if the palette has one.
std::optional<std::size_t> first_full(const Palette& palette) {
  for (std::size_t i = 0; i < palette.elements.size(); ++i)
    for (const ConvexPiece& piece : palette.elements[i].pieces)
      if (piece.empty()) return i;
  return std::nullopt;
}
std::optional<std::size_t> first_empty(const Palette& palette) {
  for (std::size_t i = 0; i < palette.elements.size(); ++i)
    if (palette.elements[i].pieces.empty()) return i;
  return std::nullopt;
}

class PaletteVoxelizer {
 public:
  PaletteVoxelizer(const Mesh& mesh, const Grid& grid, const PaletteOptions& options)
      : fixed_(mesh, grid),
        grid_(grid),
        options_(options),
        t_(options.rays),
        p_(options.points),
        n_(options.rays * options.points),
        words_((n_ + 63) / 64),
        full_(first_full(options.palette)),
        empty_(first_empty(options.palette)) {
    for (const PaletteElement& e : options.palette.elements) volumes_.push_back(element_volume(e));
  }

  PaletteVolume run(JobControl* control) {
    const Choice outside = empty_ ? Choice{static_cast<std::uint8_t>(*empty_), 255} : Choice{};
    PaletteVolume out{DenseVolume<std::uint8_t>(grid_, outside.element),
                      DenseVolume<std::uint8_t>(grid_, outside.similarity)};
    if (grid_.voxel_count() == 0) return out;
    const int threads = options_.threads > 0 ? options_.threads : default_thread_count();
    detail::for_each_ray_row<RowScratch>(
        fixed_, grid_, t_, threads, control,
        [&](std::int64_t k, RowScratch& s) {
          place_rays(k, s);
          return [this, &s](std::int64_t j, int r, std::int64_t& pu, std::int64_t& pv) {
            const std::size_t at = static_cast<std::size_t>(j * t_ + r);
            pu = s.pu[at];
            pv = s.pv[at];
          };
        },
        [&](std::int64_t k, const std::vector<RayCrossing>& crossings, RowScratch& s) {
          std::size_t c = 0;
          for (std::int64_t j = 0; j < grid_.dims.y; ++j) {
            std::size_t e = c;
            while (e < crossings.size() && crossings[e].column == j) ++e;
            // A column no ray crosses is all outside: already the empty element.
            if (e > c || !empty_) {
              const std::size_t at = static_cast<std::size_t>(j * grid_.dims.x);
              fill_column(j, crossings.data() + c, crossings.data() + e, s, out.element.slab(k) + at,
                          out.similarity.slab(k) + at);
            }
            c = e;
          }
        });
    return out;
  }

 private:
  struct RowScratch {
    std::vector<std::int64_t> pu, pv;      // ray r of column j at [j * t + r], fixed point
    std::vector<double> y, z;              // the same in voxel coordinates [0, 1)
    std::vector<double> xo;                // point q of ray r of column j at [(j * t + r) * p + q], in [0, 1)
    std::vector<Word> masks;               // element e's points at [e * words, (e + 1) * words)
    std::vector<Word> inside;              // a voxel's inside points
    std::vector<const RayCrossing*> cur, end;
    std::vector<std::uint8_t> state;       // ray r inside at the current voxel's start
  };

  // The column pattern: ray r of column j at a uniform random (y, z) in the
  // column, its p points stratified along each voxel.
  void place_rays(std::int64_t k, RowScratch& s) const {
    const std::size_t rays = static_cast<std::size_t>(grid_.dims.y * t_);
    s.pu.resize(rays);
    s.pv.resize(rays);
    s.y.resize(rays);
    s.z.resize(rays);
    s.xo.resize(rays * static_cast<std::size_t>(p_));
    const double one = static_cast<double>(kFixedOne);
    for (std::int64_t j = 0; j < grid_.dims.y; ++j)
      for (int r = 0; r < t_; ++r) {
        const std::size_t at = static_cast<std::size_t>(j * t_ + r);
        const std::uint64_t ray = static_cast<std::uint64_t>(k) << 24 ^ static_cast<std::uint64_t>(r);
        const std::uint64_t h = splitmix_hash(
            options_.seed ^ splitmix_hash(static_cast<std::uint64_t>(j) * 0x100000001b3ull ^ splitmix_hash(ray)));
        const auto du = static_cast<std::int64_t>(std::floor(unit_interval(h) * one));
        const std::uint64_t h2 = splitmix_hash(h);
        const auto dv = static_cast<std::int64_t>(std::floor(unit_interval(h2) * one));
        // Fixed point counts from the column's centre line; the column spans [-1/2, 1/2).
        s.pu[at] = j * kFixedOne - kFixedOne / 2 + du;
        s.pv[at] = k * kFixedOne - kFixedOne / 2 + dv;
        s.y[at] = static_cast<double>(du) / one;
        s.z[at] = static_cast<double>(dv) / one;
        std::uint64_t hq = h2;
        for (int q = 0; q < p_; ++q) {
          hq = splitmix_hash(hq);
          s.xo[at * static_cast<std::size_t>(p_) + static_cast<std::size_t>(q)] = (q + unit_interval(hq)) / p_;
        }
      }
  }

  void element_masks(std::int64_t j, RowScratch& s) const {
    const auto& elements = options_.palette.elements;
    s.masks.assign(elements.size() * static_cast<std::size_t>(words_), 0);
    for (std::size_t e = 0; e < elements.size(); ++e) {
      Word* mask = s.masks.data() + e * static_cast<std::size_t>(words_);
      for (int r = 0; r < t_; ++r) {
        const std::size_t at = static_cast<std::size_t>(j * t_ + r);
        for (int q = 0; q < p_; ++q) {
          const glm::dvec3 point(s.xo[at * static_cast<std::size_t>(p_) + static_cast<std::size_t>(q)], s.y[at], s.z[at]);
          if (elements[e].contains(point)) {
            const int bit = r * p_ + q;
            mask[bit >> 6] |= Word{1} << (bit & 63);
          }
        }
      }
    }
  }

  // The best element for the inside points `inside` (voxd/voxelize/palette.h).
  Choice evaluate(const std::vector<Word>& inside, const std::vector<Word>& masks) const {
    const std::size_t count = options_.palette.elements.size();
    // The occupancy statistic: the share of points inside, against which
    // equal scores are told apart by the elements' exact volumes.
    int inside_points = 0;
    for (const Word w : inside) inside_points += std::popcount(w);
    const double occupancy = static_cast<double>(inside_points) / n_;
    const auto closer = [&](std::size_t e, int than) {
      return std::abs(volumes_[e] - occupancy) < std::abs(volumes_[static_cast<std::size_t>(than)] - occupancy);
    };
    int best = -1, best_score = -1, nearest = 0, nearest_score = -1;
    for (std::size_t e = 0; e < count; ++e) {
      const Word* m = masks.data() + e * static_cast<std::size_t>(words_);
      int mismatch = 0, violations = 0;
      for (int w = 0; w < words_; ++w) {
        const Word in = inside[static_cast<std::size_t>(w)];
        const Word lost = in & ~m[w], extra = m[w] & ~in;  // object not covered, element over empty space
        mismatch += std::popcount(lost) + std::popcount(extra);
        if (options_.metric == PaletteMetric::outer) violations += std::popcount(lost);
        if (options_.metric == PaletteMetric::inner) violations += std::popcount(extra);
      }
      const int score = n_ - mismatch;
      if (score > nearest_score || (score == nearest_score && closer(e, nearest))) {
        nearest_score = score;
        nearest = static_cast<int>(e);
      }
      if (violations == 0 && (score > best_score || (score == best_score && closer(e, best)))) {
        best_score = score;
        best = static_cast<int>(e);
      }
    }
    if (best < 0) return {static_cast<std::uint8_t>(nearest), 0};
    return {static_cast<std::uint8_t>(best), static_cast<std::uint8_t>((255 * best_score + n_ / 2) / n_)};
  }

  // Inside mask of a stretch where ray r is inside iff state[r]: the shortcut
  // when all points agree, else the evaluation.
  Choice stretch_choice(std::int64_t j, bool& masks_ready, RowScratch& s) const {
    int inside_rays = 0;
    for (int r = 0; r < t_; ++r) inside_rays += s.state[static_cast<std::size_t>(r)];
    if (inside_rays == t_ && full_) return {static_cast<std::uint8_t>(*full_), 255};
    if (inside_rays == 0 && empty_) return {static_cast<std::uint8_t>(*empty_), 255};
    std::fill(s.inside.begin(), s.inside.end(), 0);
    for (int r = 0; r < t_; ++r)
      if (s.state[static_cast<std::size_t>(r)])
        for (int q = 0; q < p_; ++q) set_bit(s.inside, r * p_ + q);
    return evaluate_with_masks(j, masks_ready, s);
  }

  Choice evaluate_with_masks(std::int64_t j, bool& masks_ready, RowScratch& s) const {
    int inside_points = 0;
    for (const Word w : s.inside) inside_points += std::popcount(w);
    if (inside_points == n_ && full_) return {static_cast<std::uint8_t>(*full_), 255};
    if (inside_points == 0 && empty_) return {static_cast<std::uint8_t>(*empty_), 255};
    if (!masks_ready) {
      element_masks(j, s);
      masks_ready = true;
    }
    return evaluate(s.inside, s.masks);
  }

  static void set_bit(std::vector<Word>& bits, int bit) { bits[static_cast<std::size_t>(bit >> 6)] |= Word{1} << (bit & 63); }

  // One column: walk the voxels, in stretches where no ray crosses the
  // surface (one choice for the stretch) and single voxels where some do.
  void fill_column(std::int64_t j, const RayCrossing* begin, const RayCrossing* end, RowScratch& s,
                   std::uint8_t* element, std::uint8_t* similarity) const {
    const std::int64_t nx = grid_.dims.x;
    s.cur.assign(static_cast<std::size_t>(t_), end);
    s.end.assign(static_cast<std::size_t>(t_), end);
    s.state.assign(static_cast<std::size_t>(t_), 0);
    s.inside.assign(static_cast<std::size_t>(words_), 0);
    for (const RayCrossing* c = begin; c != end;) {
      const RayCrossing* e = c;
      while (e != end && e->ray == c->ray) ++e;
      // An odd count (an open mesh) leaves the last crossing unpaired: drop it.
      const RayCrossing* paired = (e - c) % 2 == 0 ? e : e - 1;
      const auto r = static_cast<std::size_t>(c->ray);
      s.cur[r] = c;
      s.end[r] = paired;
      // Crossings before the grid only set the state at x = 0.
      while (s.cur[r] != s.end[r] && s.cur[r]->x < 0.0) {
        s.state[r] ^= 1;
        ++s.cur[r];
      }
      c = e;
    }
    bool masks_ready = false;
    std::int64_t i = 0;
    while (i < nx) {
      std::int64_t next = nx;
      for (int r = 0; r < t_; ++r) {
        const auto rr = static_cast<std::size_t>(r);
        if (s.cur[rr] != s.end[rr]) next = std::min(next, static_cast<std::int64_t>(std::floor(s.cur[rr]->x)));
      }
      if (next > i) {
        const Choice choice = stretch_choice(j, masks_ready, s);
        std::fill(element + i, element + next, choice.element);
        std::fill(similarity + i, similarity + next, choice.similarity);
        i = next;
        continue;
      }
      // Voxel i holds crossings: each point's state is the ray's state at
      // the voxel's start, flipped by the crossings before it.
      std::fill(s.inside.begin(), s.inside.end(), 0);
      const double x0 = static_cast<double>(i);
      for (int r = 0; r < t_; ++r) {
        const auto rr = static_cast<std::size_t>(r);
        const RayCrossing* c = s.cur[rr];
        const double* xo = s.xo.data() + static_cast<std::size_t>(j * t_ + r) * static_cast<std::size_t>(p_);
        std::uint8_t in = s.state[rr];
        for (int q = 0; q < p_; ++q) {
          const double x = x0 + xo[q];
          while (c != s.end[rr] && c->x <= x) {
            in ^= 1;
            ++c;
          }
          if (in) set_bit(s.inside, r * p_ + q);
        }
        while (c != s.end[rr] && c->x < x0 + 1.0) {
          in ^= 1;
          ++c;
        }
        s.cur[rr] = c;
        s.state[rr] = in;
      }
      const Choice choice = evaluate_with_masks(j, masks_ready, s);
      element[i] = choice.element;
      similarity[i] = choice.similarity;
      ++i;
    }
  }

  detail::FixedMesh fixed_;
  Grid grid_;
  const PaletteOptions& options_;
  int t_, p_, n_, words_;
  std::optional<std::size_t> full_, empty_;
  std::vector<double> volumes_;  // exact, by element
};

}  // namespace

PaletteVolume voxelize_palette(const Mesh& mesh, const Grid& grid, const PaletteOptions& options,
                               JobControl* control) {
  if (options.rays < 1 || options.rays > 256)
    throw Error(ErrorCode::invalid_argument, "palette rays must be 1 to 256 per column, got " + std::to_string(options.rays));
  if (options.points < 1 || options.points > 64)
    throw Error(ErrorCode::invalid_argument,
                "palette points must be 1 to 64 per voxel and ray, got " + std::to_string(options.points));
  if (options.rays * options.points > 4096)
    throw Error(ErrorCode::invalid_argument, "palette rays x points must be at most 4096 sample points per voxel, got " +
                                                 std::to_string(options.rays * options.points));
  validate(options.palette);
  PaletteVoxelizer v(mesh, grid, options);
  return v.run(control);
}

}  // namespace voxd
