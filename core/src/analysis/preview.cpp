#include "voxd/analysis/preview.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <span>

#include <glm/geometric.hpp>

#include "voxd/error.h"
#include "voxd/parallel.h"
#include "voxd/uncleared_vector.h"
#include "voxd/analysis/radiography.h"
#include "run_rows.h"

namespace voxd {
namespace {

void check_axis(int axis) {
  if (axis < 0 || axis > 2) {
    throw Error(ErrorCode::invalid_argument, "view axis must be 0 (x), 1 (y) or 2 (z), got " + std::to_string(axis));
  }
}

glm::vec3 axis_vector(int axis, bool positive) {
  glm::vec3 v(0.0f);
  v[axis] = positive ? 1.0f : -1.0f;
  return v;
}

// The 26 neighbour offsets with their unit directions, computed once so the
// per-voxel normal is a sum of table entries.
struct Neighbour {
  int di, dj, dk;
  glm::vec3 unit;
};
const std::array<Neighbour, 26>& neighbours() {
  static const std::array<Neighbour, 26> table = [] {
    std::array<Neighbour, 26> t{};
    std::size_t n = 0;
    for (int dk = -1; dk <= 1; ++dk)
      for (int dj = -1; dj <= 1; ++dj)
        for (int di = -1; di <= 1; ++di)
          if (di != 0 || dj != 0 || dk != 0) {
            t[n++] = {di, dj, dk, glm::normalize(glm::vec3(static_cast<float>(di), static_cast<float>(dj), static_cast<float>(dk)))};
          }
    return t;
  }();
  return table;
}

// Patil & Ravi: empty neighbours (the grid's outside included) lie on the
// outer side of the surface, so their unit offsets sum to the outward normal.
// filled(a, b, c) answers for a voxel inside the grid.
template <typename Filled>
glm::vec3 neighbour_normal(const glm::i64vec3& d, const Filled& filled, std::int64_t i, std::int64_t j, std::int64_t k,
                           glm::vec3 fallback) {
  glm::vec3 n(0.0f);
  for (const Neighbour& e : neighbours()) {
    const std::int64_t a = i + e.di, b = j + e.dj, c = k + e.dk;
    const bool inside = a >= 0 && b >= 0 && c >= 0 && a < d.x && b < d.y && c < d.z;
    if (!inside || !filled(a, b, c)) n += e.unit;
  }
  const float len = glm::length(n);
  return len < 1e-4f ? fallback : n / len;
}

bool bit_of(const std::uint64_t* row, std::int64_t i) { return (row[i >> 6] >> (i & 63)) & 1u; }

using detail::for_each_difference;
using detail::last_layers;
using detail::Runs;

// Bits i - 1, i and i + 1 of a row of runs (bit 0 for i - 1): one search,
// then a step or two.
unsigned three_bits(Runs row, std::int64_t i) {
  std::size_t pos = static_cast<std::size_t>(
      std::upper_bound(row.begin(), row.end(), static_cast<std::uint32_t>(std::max<std::int64_t>(i - 1, 0))) - row.begin());
  if (i == 0) pos = 0;  // x = -1 precedes every bound
  unsigned bits = 0;
  for (std::int64_t x = i - 1; x <= i + 1; ++x) {
    while (pos < row.size() && static_cast<std::int64_t>(row[pos]) <= x) ++pos;
    if (pos & 1u) bits |= 1u << (x - (i - 1));
  }
  return bits;
}

// The words of `w` covering [begin, end), as a mask within word w.
std::uint64_t range_mask(std::int64_t w, std::int64_t begin, std::int64_t end) {
  const std::int64_t lo = std::max(begin, w * 64) - w * 64, hi = std::min(end, w * 64 + 64) - w * 64;
  const std::uint64_t upto = hi == 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << hi) - 1;
  return upto & ~((std::uint64_t{1} << lo) - 1);
}

}  // namespace

std::optional<View> parse_view(std::string_view text) {
  View v;
  if (text.size() == 2) {
    if (text[0] != '+' && text[0] != '-') return std::nullopt;
    v.from_positive = text[0] == '+';
    text.remove_prefix(1);
  }
  if (text.size() != 1 || text[0] < 'x' || text[0] > 'z') return std::nullopt;
  v.axis = text[0] - 'x';
  return v;
}

std::string to_string(View v) {
  check_axis(v.axis);
  return std::string(v.from_positive ? "+" : "-") + "xyz"[v.axis];
}

ViewBasis view_basis(View v) {
  check_axis(v.axis);
  // Chosen so that right x up = -f (right-handed, the camera looking along f):
  // turning the camera round to the opposite side flips `right`, never `up`.
  switch (v.axis) {
    case 0: return {1, v.from_positive, 2, true};
    case 1: return {0, !v.from_positive, 2, true};
    default: return {0, v.from_positive, 1, true};
  }
}

struct PreviewRenderer::State {
  State(const Grid& g, View v, int t, int max_side)
      : grid(g), view(v), basis(view_basis(v)), threads(t), dims(g.dims), nx(dims.x), ny(dims.y), nz(dims.z),
        n_right(dims[basis.right_axis]), n_up(dims[basis.up_axis]), n_depth(dims[v.axis]),
        words((nx + 63) / 64),
        forward(axis_vector(v.axis, !v.from_positive)),
        right(axis_vector(basis.right_axis, basis.right_positive)),
        up(axis_vector(basis.up_axis, basis.up_positive)) {
    const ImageSize size = projected_size(g, v.axis);  // same extents as the basis, with the INT_MAX check
    img.width = size.width;
    img.height = size.height;
    width = img.width;
    pixels = static_cast<std::size_t>(img.width) * static_cast<std::size_t>(img.height);
    factor = pixels > 0 ? shrink_factor(img.width, img.height, max_side) : 1;
    // Shrunk, the raw normals are 9 a block, counted in 32 bits like pixels.
    const std::uint64_t blocks = static_cast<std::uint64_t>((img.width + factor - 1) / factor) *
                                 static_cast<std::uint64_t>((img.height + factor - 1) / factor);
    if (factor > 1 && 9 * blocks > std::numeric_limits<std::uint32_t>::max())
      throw Error(ErrorCode::limit_exceeded, "preview: " + std::to_string(blocks) +
                                                 " pixels to shrink to is too many (ask for a smaller size)");
    if (factor == 1) {  // shrunk, the pixels keep only their depths
      img.voxel.assign(pixels, -1);
      img.shade.assign(pixels, 0.0f);
      img.normal.assign(pixels, glm::vec3(0.0f));
    }
    assign_on_every_thread(depth, pixels, std::int32_t{-1}, threads);
  }
  // What it made on every thread (hundreds of megabytes for a large grid's
  // preview) given back the same way, not by the thread that frees it.
  ~State() {
    free_on_every_thread(raw, threads);
    free_on_every_thread(depth, threads);
    free_on_every_thread(chosen, threads);
    free_on_every_thread(by_layer, threads);
  }
  State(const State&) = delete;
  State& operator=(const State&) = delete;

  // What shade() computes a raw normal for, a target: a visible pixel, or
  // (shrunk) each block's 3x3 pixels around its chosen one (target
  // 9 block + 3 (dr + 1) + dc + 1) that its smoothing takes in.
  std::size_t target_count() const { return factor == 1 ? pixels : chosen.size() * 9; }
  std::int64_t target_pixel(std::size_t t) const {
    if (factor == 1) return static_cast<std::int64_t>(t);
    const auto o = static_cast<std::int64_t>(t % 9);
    return chosen[t / 9] + (o / 3 - 1) * width + o % 3 - 1;
  }
  // Whether pixel q is smoothed into pixel p's normal (q next to p).
  bool smoothed_into(std::size_t q, std::size_t p) const { return depth[q] >= 0 && std::abs(depth[q] - depth[p]) <= 2; }
  bool needed(std::size_t t) const {
    if (factor == 1) return img.voxel[t] >= 0;
    const std::int64_t p = chosen[t / 9];
    if (p < 0) return false;
    const auto o = static_cast<std::int64_t>(t % 9);
    const std::int64_t r = p / width + o / 3 - 1, c = p % width + o % 3 - 1;
    return r >= 0 && c >= 0 && r < img.height && c < width &&
           smoothed_into(static_cast<std::size_t>(r * width + c), static_cast<std::size_t>(p));
  }

  // Column <-> coordinate along the right axis, row <-> coordinate along up
  // (row 0 at the top); each is its own inverse.
  std::int64_t along_right(std::int64_t c) const { return basis.right_positive ? c : n_right - 1 - c; }
  std::int64_t along_up(std::int64_t r) const { return basis.up_positive ? n_up - 1 - r : r; }
  std::size_t layer_words() const { return static_cast<std::size_t>(words * ny); }

  void see(std::size_t p, std::int64_t i, std::int64_t j, std::int64_t k, std::int64_t distance) {
    if (factor == 1) img.voxel[p] = i + nx * (j + ny * k);
    depth[p] = static_cast<std::int32_t>(distance);
  }
  // Pixel p's visible voxel (it has one): kept at full size, else where its
  // ray meets its depth.
  std::int64_t voxel_at(std::size_t p) const {
    if (factor == 1) return img.voxel[p];
    const auto at = static_cast<std::int64_t>(p);
    std::int64_t ijk[3];
    ijk[basis.right_axis] = along_right(at % width);
    ijk[basis.up_axis] = along_up(at / width);
    ijk[view.axis] = view.from_positive ? n_depth - 1 - depth[p] : depth[p];
    return ijk[0] + nx * (ijk[1] + ny * ijk[2]);
  }

  void find_x(std::int64_t k0, const BitVolume& slab);
  void find_y(std::int64_t k0, const BitVolume& slab);
  void find_z(std::int64_t k0, const BitVolume& slab);
  void find_x(std::int64_t k0, const RunSlab& slab);
  template <typename WordsOf>
  void find_y_words(std::int64_t k0, std::int64_t n, const WordsOf& words_of);
  void find_y(std::int64_t k0, const RunSlab& slab);
  void find_z(std::int64_t k0, const RunSlab& slab);
  void choose();
  void sort_by_layer();
  // The raw normals of the pixels whose visible voxel lies in layers
  // [k0 - 1, k0 + n - 1) (all of them at the top); normal_of(v) gives voxel
  // v's.
  template <typename NormalOf>
  void shade_layers(std::int64_t k0, std::int64_t n, const NormalOf& normal_of);
  void light();
  // A pass takes all its slabs as bits or all as runs (its seam is kept so).
  enum class Kind { none, bits, runs };
  static void check_kind(Kind& pass, Kind slab, const char* name) {
    if (pass != Kind::none && pass != slab)
      throw std::logic_error(std::string("PreviewRenderer::") + name + ": a pass takes all its slabs as bits or all as runs");
    pass = slab;
  }
  // Either kind of slab: its order checked, then the view's find.
  template <typename Slab>
  void find_in(std::int64_t k0, const Slab& slab, Kind kind);
  bool start_shade(std::int64_t k0, const Grid& slab, Kind kind);

  Grid grid;
  View view;
  ViewBasis basis;
  int threads;
  glm::i64vec3 dims;
  std::int64_t nx, ny, nz, n_right, n_up, n_depth, words, width = 0;
  std::size_t pixels = 0;
  glm::vec3 forward, right, up;
  PreviewImage img;
  // Distance of the visible voxel from the camera side, in voxels; -1 = background.
  UnclearedVector<std::int32_t> depth;
  // The unsmoothed normals, a target's each. Made (tens of megabytes for a
  // large grid's preview) and zeroed on every thread, not the calling one.
  UnclearedVector<glm::vec3> raw;
  // Shrunk (max_side): each pixel of `out` stands for a block of factor x
  // factor rendered ones and shows the block's chosen pixel (its nearest
  // visible voxel, as shrink_preview), whose normal alone is smoothed and lit.
  int factor = 1;
  UnclearedVector<std::int64_t> chosen;  // a block's chosen pixel, -1 for none (choose writes each)
  PreviewImage out;
  std::int64_t found_to = 0, shaded_to = 0;  // layers each pass has seen
  std::vector<std::uint64_t> last_layer;     // find along z: the layer before the slab
  std::vector<std::uint64_t> before[2];      // shade: layers shaded_to - 2 and shaded_to - 1
  RunSlab last_runs, before_runs;            // the same seams for slabs of runs
  Kind find_kind = Kind::none, shade_kind = Kind::none;
  // shade: the pixels by their visible voxel's layer (a counting sort).
  std::vector<std::int64_t> layer_start;
  UnclearedVector<std::uint32_t> by_layer;  // written whole by the sort
};

// Rays along the x rows: the visible voxel is the row's highest (+x) or
// lowest (-x) set bit, found a word at a time.
void PreviewRenderer::State::find_x(std::int64_t k0, const BitVolume& slab) {
  parallel_for(k0, k0 + slab.grid().dims.z, 1, threads, [&](std::int64_t a, std::int64_t b) {
    for (std::int64_t k = a; k < b; ++k) {
      const std::int64_t r = along_up(k);
      for (std::int64_t c = 0; c < width; ++c) {
        const std::int64_t j = along_right(c);
        const std::uint64_t* row = slab.row(j, k - k0);
        std::int64_t i = -1;
        if (view.from_positive) {
          for (std::int64_t w = words - 1; w >= 0 && i < 0; --w) {
            if (row[w]) i = w * 64 + 63 - std::countl_zero(row[w]);
          }
        } else {
          for (std::int64_t w = 0; w < words && i < 0; ++w) {
            if (row[w]) i = w * 64 + std::countr_zero(row[w]);
          }
        }
        if (i >= 0) see(static_cast<std::size_t>(r * width + c), i, j, k, view.from_positive ? n_depth - 1 - i : i);
      }
    }
  });
}

// Rays along y cross the x rows of one layer: walk them from the camera
// side, taking the bits not yet found, until every column has its voxel or
// the layer ends. words_of(j, kk, take) calls take(w, bits) for each word
// of slab row (j, kk) that may hold voxels.
template <typename WordsOf>
void PreviewRenderer::State::find_y_words(std::int64_t k0, std::int64_t n, const WordsOf& words_of) {
  parallel_for(k0, k0 + n, 1, threads, [&](std::int64_t a, std::int64_t b) {
    std::vector<std::uint64_t> found(static_cast<std::size_t>(words));
    for (std::int64_t k = a; k < b; ++k) {
      const std::int64_t r = along_up(k);
      std::fill(found.begin(), found.end(), 0);
      std::int64_t remaining = nx;
      for (std::int64_t s = 0; s < n_depth && remaining > 0; ++s) {
        const std::int64_t j = view.from_positive ? n_depth - 1 - s : s;
        words_of(j, k - k0, [&](std::int64_t w, std::uint64_t bits) {
          std::uint64_t fresh = bits & ~found[static_cast<std::size_t>(w)];
          if (!fresh) return;
          found[static_cast<std::size_t>(w)] |= fresh;
          remaining -= std::popcount(fresh);
          for (; fresh; fresh &= fresh - 1) {
            const std::int64_t i = w * 64 + std::countr_zero(fresh);
            see(static_cast<std::size_t>(r * width + along_right(i)), i, j, k, s);
          }
        });
      }
    }
  });
}

void PreviewRenderer::State::find_y(std::int64_t k0, const BitVolume& slab) {
  find_y_words(k0, slab.grid().dims.z, [&](std::int64_t j, std::int64_t kk, const auto& take) {
    const std::uint64_t* row = slab.row(j, kk);
    for (std::int64_t w = 0; w < words; ++w)
      if (row[w]) take(w, row[w]);
  });
}

// Rays along z cross the slabs: a run of a ray begins at a layer whose bit is
// set where the layer before's is clear, and ends where it is clear after a
// set one. From -z the visible voxel is the first run's first; from +z the
// last run's last (the layer before its end, or the top layer).
void PreviewRenderer::State::find_z(std::int64_t k0, const BitVolume& slab) {
  const std::int64_t n = slab.grid().dims.z, k1 = k0 + n;
  const bool from_top = view.from_positive;
  parallel_for(0, ny, 8, threads, [&](std::int64_t j0, std::int64_t j1) {
    const std::vector<std::uint64_t> none(static_cast<std::size_t>(words), 0);
    for (std::int64_t j = j0; j < j1; ++j) {
      const std::int64_t r = along_up(j);
      for (std::int64_t k = k0; k < k1; ++k) {
        const std::uint64_t* cur = slab.row(j, k - k0);
        const std::uint64_t* prev = k > k0    ? slab.row(j, k - 1 - k0)
                                    : k0 > 0 ? last_layer.data() + j * words
                                             : none.data();
        for (std::int64_t w = 0; w < words; ++w) {
          for (std::uint64_t changed = cur[w] ^ prev[w]; changed; changed &= changed - 1) {
            const int b = std::countr_zero(changed);
            const std::int64_t i = w * 64 + b;
            const std::size_t p = static_cast<std::size_t>(r * width + along_right(i));
            const bool begins = (cur[w] >> b) & 1u;
            if (begins && !from_top && depth[p] < 0) see(p, i, j, k, k);
            if (!begins && from_top) see(p, i, j, k - 1, n_depth - k);
          }
        }
        if (k == nz - 1 && from_top) {
          for (std::int64_t w = 0; w < words; ++w)
            for (std::uint64_t open = cur[w]; open; open &= open - 1) {
              const std::int64_t i = w * 64 + std::countr_zero(open);
              see(static_cast<std::size_t>(r * width + along_right(i)), i, j, k, 0);
            }
        }
      }
    }
  });
  if (k1 < nz) {
    const std::uint64_t* top = slab.slab(n - 1);
    last_layer.assign(top, top + layer_words());
  }
}

// The same three from runs: the row's first or last run; the runs walked
// from the camera side; the differences of each row's runs from the layer
// before's (where runs begin and end along z).
void PreviewRenderer::State::find_x(std::int64_t k0, const RunSlab& slab) {
  parallel_for(k0, k0 + slab.grid().dims.z, 1, threads, [&](std::int64_t a, std::int64_t b) {
    for (std::int64_t k = a; k < b; ++k) {
      const std::int64_t r = along_up(k);
      for (std::int64_t c = 0; c < width; ++c) {
        const std::int64_t j = along_right(c);
        const Runs row = slab.row(j, k - k0);
        if (row.empty()) continue;
        const std::int64_t i = view.from_positive ? std::int64_t{row.back()} - 1 : std::int64_t{row.front()};
        see(static_cast<std::size_t>(r * width + c), i, j, k, view.from_positive ? n_depth - 1 - i : i);
      }
    }
  });
}

void PreviewRenderer::State::find_y(std::int64_t k0, const RunSlab& slab) {
  find_y_words(k0, slab.grid().dims.z, [&](std::int64_t j, std::int64_t kk, const auto& take) {
    const Runs row = slab.row(j, kk);
    for (std::size_t x = 0; x < row.size(); x += 2) {
      const std::int64_t begin = row[x], end = row[x + 1];
      for (std::int64_t w = begin / 64; w * 64 < end; ++w) take(w, range_mask(w, begin, end));
    }
  });
}

void PreviewRenderer::State::find_z(std::int64_t k0, const RunSlab& slab) {
  const std::int64_t n = slab.grid().dims.z, k1 = k0 + n;
  const bool from_top = view.from_positive;
  parallel_for(0, ny, 8, threads, [&](std::int64_t j0, std::int64_t j1) {
    for (std::int64_t j = j0; j < j1; ++j) {
      const std::int64_t r = along_up(j);
      const auto pixel = [&](std::int64_t i) { return static_cast<std::size_t>(r * width + along_right(i)); };
      for (std::int64_t k = k0; k < k1; ++k) {
        const Runs cur = slab.row(j, k - k0);
        const Runs prev = k > k0 ? slab.row(j, k - 1 - k0) : k0 > 0 ? last_runs.row(j, 0) : Runs{};
        if (!from_top) {
          for_each_difference(cur, prev, [&](std::int64_t b, std::int64_t e) {
            for (std::int64_t i = b; i < e; ++i)
              if (depth[pixel(i)] < 0) see(pixel(i), i, j, k, k);
          });
        } else {
          for_each_difference(prev, cur, [&](std::int64_t b, std::int64_t e) {
            for (std::int64_t i = b; i < e; ++i) see(pixel(i), i, j, k - 1, n_depth - k);
          });
          if (k == nz - 1)
            for (std::size_t x = 0; x < cur.size(); x += 2)
              for (std::int64_t i = cur[x]; i < cur[x + 1]; ++i) see(pixel(i), i, j, k, 0);
        }
      }
    }
  });
  if (k1 < nz) last_runs = last_layers(last_runs, slab, 1);
}

// Shrunk: each block's chosen pixel, as shrink_preview picks it (the least
// depth is the nearest voxel; ties: the first in row order).
void PreviewRenderer::State::choose() {
  out.width = (img.width + factor - 1) / factor;
  out.height = (img.height + factor - 1) / factor;
  out.block = factor;
  const auto blocks = static_cast<std::size_t>(out.width) * static_cast<std::size_t>(out.height);
  out.voxel.assign(blocks, -1);
  out.shade.assign(blocks, 0.0f);
  out.normal.assign(blocks, glm::vec3(0.0f));
  chosen.resize(blocks);
  parallel_for(0, out.height, 4, threads, [&](std::int64_t b0, std::int64_t b1) {
    for (std::int64_t row = b0; row < b1; ++row)
      for (std::int64_t col = 0; col < out.width; ++col) {
        std::int64_t best = -1;
        for (std::int64_t r = row * factor; r < std::min<std::int64_t>(img.height, (row + 1) * factor); ++r)
          for (std::int64_t c = col * factor; c < std::min<std::int64_t>(width, (col + 1) * factor); ++c) {
            const std::int64_t p = r * width + c;
            if (depth[static_cast<std::size_t>(p)] >= 0 &&
                (best < 0 || depth[static_cast<std::size_t>(p)] < depth[static_cast<std::size_t>(best)]))
              best = p;
          }
        chosen[static_cast<std::size_t>(row * out.width + col)] = best;
      }
  });
}

// A counting sort of the targets by their voxel's layer, on every thread:
// contiguous chunks of targets counted and placed each on its own, the
// chunks' offsets in a layer in chunk order, so the order within a layer is
// the targets' whatever the threads.
void PreviewRenderer::State::sort_by_layer() {
  if (factor > 1) choose();
  const std::int64_t per_layer = nx * ny;
  const auto targets = static_cast<std::int64_t>(target_count());
  const auto layers = static_cast<std::size_t>(nz);
  const auto layer_of = [&](std::int64_t t) {
    return static_cast<std::size_t>(voxel_at(static_cast<std::size_t>(target_pixel(static_cast<std::size_t>(t)))) /
                                    per_layer);
  };
  const std::int64_t chunks = std::clamp<std::int64_t>(targets >> 16, 1, 64);
  const std::int64_t per_chunk = (targets + chunks - 1) / chunks;
  std::vector<std::int64_t> at(static_cast<std::size_t>(chunks) * layers, 0);  // chunk-major
  const auto each_chunk = [&](const auto& visit) {
    parallel_for(0, chunks, 1, threads, [&](std::int64_t c0, std::int64_t c1) {
      for (std::int64_t c = c0; c < c1; ++c) {
        std::int64_t* slot = at.data() + static_cast<std::size_t>(c) * layers;
        for (std::int64_t t = c * per_chunk; t < std::min(targets, (c + 1) * per_chunk); ++t)
          if (needed(static_cast<std::size_t>(t))) visit(slot[layer_of(t)], t);
      }
    });
  };
  each_chunk([](std::int64_t& count, std::int64_t) { ++count; });
  layer_start.assign(layers + 1, 0);
  std::int64_t placed = 0;
  for (std::size_t k = 0; k < layers; ++k) {
    layer_start[k] = placed;
    for (std::int64_t c = 0; c < chunks; ++c) {
      std::int64_t& slot = at[static_cast<std::size_t>(c) * layers + k];
      const std::int64_t count = slot;
      slot = placed;
      placed += count;
    }
  }
  layer_start[layers] = placed;
  by_layer.resize(static_cast<std::size_t>(placed));
  each_chunk([&](std::int64_t& next, std::int64_t t) { by_layer[static_cast<std::size_t>(next++)] = static_cast<std::uint32_t>(t); });
  assign_on_every_thread(raw, static_cast<std::size_t>(targets), glm::vec3(0.0f), threads);
}

// Screen-space smoothing of the normals, then the lighting.
void PreviewRenderer::State::light() {
  std::int32_t nearest = std::numeric_limits<std::int32_t>::max(), farthest = -1;
  for (const std::int32_t d : depth) {
    if (d < 0) continue;
    nearest = std::min(nearest, d);
    farthest = std::max(farthest, d);
  }
  if (farthest < 0) return;  // nothing visible
  const float depth_span = static_cast<float>(farthest - nearest);

  const glm::vec3 light = glm::normalize(-forward + 0.5f * up - 0.35f * right);
  // Pixel (r, c)'s normal and shade into normal and shade; raw_of(rr, cc)
  // the raw normal of a pixel around it.
  const auto lit = [&](std::int64_t r, std::int64_t c, const auto& raw_of, glm::vec3& normal, float& shade) {
    const std::size_t p = static_cast<std::size_t>(r * width + c);
    const std::int32_t d0 = depth[p];
    // Screen-space smoothing hides the voxel staircase; the depth test
    // keeps a silhouette from averaging with a surface far behind it.
    glm::vec3 sum(0.0f);
    for (std::int64_t rr = std::max<std::int64_t>(r - 1, 0); rr <= std::min<std::int64_t>(r + 1, img.height - 1); ++rr) {
      for (std::int64_t cc = std::max<std::int64_t>(c - 1, 0); cc <= std::min<std::int64_t>(c + 1, width - 1); ++cc) {
        if (smoothed_into(static_cast<std::size_t>(rr * width + cc), p)) sum += raw_of(rr, cc);
      }
    }
    const float len = glm::length(sum);
    const glm::vec3 n = len < 1e-4f ? raw_of(r, c) : sum / len;
    const float t = depth_span > 0.0f ? static_cast<float>(d0 - nearest) / depth_span : 0.0f;
    normal = n;
    shade = std::clamp((0.2f + 0.8f * std::max(0.0f, glm::dot(n, light))) * (1.0f - 0.2f * t), 0.0f, 1.0f);
  };
  if (factor == 1) {
    parallel_for(0, img.height, 8, threads, [&](std::int64_t r0, std::int64_t r1) {
      const auto raw_of = [&](std::int64_t rr, std::int64_t cc) { return raw[static_cast<std::size_t>(rr * width + cc)]; };
      for (std::int64_t r = r0; r < r1; ++r)
        for (std::int64_t c = 0; c < width; ++c) {
          const std::size_t p = static_cast<std::size_t>(r * width + c);
          if (depth[p] >= 0) lit(r, c, raw_of, img.normal[p], img.shade[p]);
        }
    });
    return;
  }
  // Shrunk: each block's chosen pixel, from the raw normals kept for it.
  parallel_for(0, static_cast<std::int64_t>(chosen.size()), 4096, threads, [&](std::int64_t b0, std::int64_t b1) {
    for (std::int64_t b = b0; b < b1; ++b) {
      const std::int64_t p = chosen[static_cast<std::size_t>(b)];
      if (p < 0) continue;
      const std::int64_t r = p / width, c = p % width;
      const auto raw_of = [&](std::int64_t rr, std::int64_t cc) {
        return raw[static_cast<std::size_t>(9 * b + 3 * (rr - r + 1) + cc - c + 1)];
      };
      const auto q = static_cast<std::size_t>(b);
      out.voxel[q] = voxel_at(static_cast<std::size_t>(p));
      lit(r, c, raw_of, out.normal[q], out.shade[q]);
    }
  });
}

PreviewRenderer::PreviewRenderer(const Grid& grid, View view, int threads, int max_side) {
  check_axis(view.axis);
  state_ = std::make_unique<State>(grid, view, threads, max_side);
}

PreviewRenderer::~PreviewRenderer() = default;

namespace {

void check_slab(const Grid& grid, std::int64_t expected_k0, std::int64_t k0, const Grid& slab, const char* pass) {
  const glm::i64vec3 d = slab.dims;
  if (k0 != expected_k0 || d.x != grid.dims.x || d.y != grid.dims.y || k0 + d.z > grid.dims.z)
    throw std::logic_error(std::string("PreviewRenderer::") + pass + ": slabs must come in z order, whole layers of the grid");
}

}  // namespace

template <typename Slab>
void PreviewRenderer::State::find_in(std::int64_t k0, const Slab& slab, Kind kind) {
  check_slab(grid, found_to, k0, slab.grid(), "find");
  check_kind(find_kind, kind, "find");
  if (pixels > 0) {
    if (view.axis == 0) find_x(k0, slab);
    else if (view.axis == 1) find_y(k0, slab);
    else find_z(k0, slab);
  }
  found_to = k0 + slab.grid().dims.z;
}

void PreviewRenderer::find(std::int64_t k0, const BitVolume& slab) { state_->find_in(k0, slab, State::Kind::bits); }
void PreviewRenderer::find(std::int64_t k0, const RunSlab& slab) { state_->find_in(k0, slab, State::Kind::runs); }

template <typename NormalOf>
void PreviewRenderer::State::shade_layers(std::int64_t k0, std::int64_t n, const NormalOf& normal_of) {
  const std::int64_t k1 = k0 + n;
  if (k0 == 0) sort_by_layer();
  // The pixels seeing layers lo..hi: the layer left from the slab before
  // (it needed this slab's first), and this slab's but its last (it needs
  // the next slab's first), all of them at the top.
  const std::int64_t lo = k0 > 0 ? k0 - 1 : 0, hi = k1 == nz ? k1 - 1 : k1 - 2;
  if (hi < lo) return;
  const std::int64_t p0 = layer_start[static_cast<std::size_t>(lo)], p1 = layer_start[static_cast<std::size_t>(hi + 1)];
  parallel_for(p0, p1, 1024, threads, [&](std::int64_t a, std::int64_t b) {
    for (std::int64_t q = a; q < b; ++q) {
      const std::size_t t = by_layer[static_cast<std::size_t>(q)];
      raw[t] = normal_of(voxel_at(static_cast<std::size_t>(target_pixel(t))));
    }
  });
}

// A slab for shade(), checked and counted: whether there are pixels to shade.
bool PreviewRenderer::State::start_shade(std::int64_t k0, const Grid& slab, Kind kind) {
  if (found_to != nz) throw std::logic_error("PreviewRenderer::shade before find() has seen every layer");
  check_slab(grid, shaded_to, k0, slab, "shade");
  check_kind(shade_kind, kind, "shade");
  shaded_to = k0 + slab.dims.z;
  return pixels > 0;
}

void PreviewRenderer::shade(std::int64_t k0, const BitVolume& slab) {
  State& s = *state_;
  if (!s.start_shade(k0, slab.grid(), State::Kind::bits)) return;
  const std::int64_t n = slab.grid().dims.z, k1 = k0 + n;
  const std::uint64_t* layer_before[2] = {s.before[0].data(), s.before[1].data()};
  const auto filled = [&](std::int64_t a, std::int64_t b, std::int64_t c) {
    if (c >= k0) return slab.get(a, b, c - k0);
    return bit_of(layer_before[c - (k0 - 2)] + b * s.words, a);
  };
  s.shade_layers(k0, n, [&](std::int64_t v) {
    return neighbour_normal(s.dims, filled, v % s.nx, (v / s.nx) % s.ny, v / (s.nx * s.ny), -s.forward);
  });
  if (k1 < s.nz) {
    // The two layers the next slab's seam needs.
    if (n >= 2) s.before[0].assign(slab.slab(n - 2), slab.slab(n - 2) + s.layer_words());
    else s.before[0] = std::move(s.before[1]);
    s.before[1].assign(slab.slab(n - 1), slab.slab(n - 1) + s.layer_words());
  } else {
    s.light();
  }
}

void PreviewRenderer::shade(std::int64_t k0, const RunSlab& slab) {
  State& s = *state_;
  if (!s.start_shade(k0, slab.grid(), State::Kind::runs)) return;
  const std::int64_t n = slab.grid().dims.z, k1 = k0 + n;
  const auto row = [&](std::int64_t b, std::int64_t c) {
    return c >= k0 ? slab.row(b, c - k0) : s.before_runs.row(b, c - (k0 - 2));
  };
  s.shade_layers(k0, n, [&](std::int64_t v) {
    const std::int64_t i = v % s.nx, j = (v / s.nx) % s.ny, k = v / (s.nx * s.ny);
    // The 27 bits around the voxel from 9 rows (bit (dk, dj, di) + 1 each),
    // then the same normal as from bits.
    std::uint32_t around = 0;
    for (std::int64_t dk = -1; dk <= 1; ++dk)
      for (std::int64_t dj = -1; dj <= 1; ++dj) {
        const std::int64_t b = j + dj, c = k + dk;
        if (b < 0 || c < 0 || b >= s.ny || c >= s.nz) continue;
        around |= three_bits(row(b, c), i) << (9 * (dk + 1) + 3 * (dj + 1));
      }
    const auto filled = [&](std::int64_t a, std::int64_t b, std::int64_t c) {
      return (around >> (9 * (c - k + 1) + 3 * (b - j + 1) + (a - i + 1))) & 1u;
    };
    return neighbour_normal(s.dims, filled, i, j, k, -s.forward);
  });
  if (k1 < s.nz) {
    s.before_runs = last_layers(s.before_runs, slab, 2);
  } else {
    s.light();
  }
}

PreviewImage PreviewRenderer::take() {
  State& s = *state_;
  if (s.pixels > 0 && (s.found_to != s.nz || s.shaded_to != s.nz))
    throw std::logic_error("PreviewRenderer::take before both passes have seen every layer");
  if (s.factor == 1) return std::move(s.img);
  if (s.chosen.empty()) s.choose();  // no layers: every block background
  return std::move(s.out);
}

PreviewImage render_preview(const BitVolume& volume, View view, int threads, int max_side) {
  PreviewRenderer renderer(volume.grid(), view, threads, max_side);
  if (volume.grid().dims.z > 0) {
    renderer.find(0, volume);
    renderer.shade(0, volume);
  }
  return renderer.take();
}

}  // namespace voxd
