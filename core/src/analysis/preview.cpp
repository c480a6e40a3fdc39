#include "voxd/analysis/preview.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>

#include "voxd/error.h"
#include "voxd/parallel.h"
#include "voxd/analysis/radiography.h"

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
glm::vec3 neighbour_normal(const BitVolume& v, std::int64_t i, std::int64_t j, std::int64_t k, glm::vec3 fallback) {
  const glm::i64vec3 d = v.grid().dims;
  glm::vec3 n(0.0f);
  for (const Neighbour& e : neighbours()) {
    const std::int64_t a = i + e.di, b = j + e.dj, c = k + e.dk;
    const bool inside = a >= 0 && b >= 0 && c >= 0 && a < d.x && b < d.y && c < d.z;
    if (!inside || !v.get(a, b, c)) n += e.unit;
  }
  const float len = glm::length(n);
  return len < 1e-4f ? fallback : n / len;
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

PreviewImage render_preview(const BitVolume& volume, View view, int threads) {
  check_axis(view.axis);
  const ViewBasis basis = view_basis(view);
  const ImageSize size = projected_size(volume.grid(), view.axis);  // same extents as the basis, with the INT_MAX check
  const glm::i64vec3 dims = volume.grid().dims;
  const std::int64_t nx = dims.x, ny = dims.y;
  const std::int64_t n_right = dims[basis.right_axis], n_up = dims[basis.up_axis], n_depth = dims[view.axis];

  PreviewImage img;
  img.width = size.width;
  img.height = size.height;
  const std::size_t pixels = static_cast<std::size_t>(img.width) * static_cast<std::size_t>(img.height);
  img.voxel.assign(pixels, -1);
  img.shade.assign(pixels, 0.0f);
  img.normal.assign(pixels, glm::vec3(0.0f));
  if (pixels == 0) return img;

  const glm::vec3 forward = axis_vector(view.axis, !view.from_positive);
  const glm::vec3 right = axis_vector(basis.right_axis, basis.right_positive);
  const glm::vec3 up = axis_vector(basis.up_axis, basis.up_positive);
  // Column <-> coordinate along the right axis, row <-> coordinate along up (row 0 at the top).
  auto along_right = [&](std::int64_t c) { return basis.right_positive ? c : n_right - 1 - c; };
  auto along_up = [&](std::int64_t r) { return basis.up_positive ? n_up - 1 - r : r; };

  // Distance of the visible voxel from the camera side, in voxels; -1 = background.
  std::vector<std::int32_t> depth(pixels, -1);
  std::vector<glm::vec3> raw(pixels, glm::vec3(0.0f));
  const std::int64_t width = img.width;
  const std::int64_t words = volume.row_words();

  parallel_for(0, img.height, 8, threads, [&](std::int64_t r0, std::int64_t r1) {
    std::vector<std::uint64_t> found(static_cast<std::size_t>(words));
    for (std::int64_t r = r0; r < r1; ++r) {
      const std::int64_t u = along_up(r);
      std::int64_t* voxel = img.voxel.data() + r * width;
      std::int32_t* dist = depth.data() + r * width;
      if (view.axis == 0) {
        // Rays run along the x rows: the visible voxel is the row's highest
        // (+x) or lowest (-x) set bit, found a word at a time.
        for (std::int64_t c = 0; c < width; ++c) {
          const std::int64_t j = along_right(c);
          const std::uint64_t* row = volume.row(j, u);
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
          if (i < 0) continue;
          voxel[c] = i + nx * (j + ny * u);
          dist[c] = static_cast<std::int32_t>(view.from_positive ? n_depth - 1 - i : i);
        }
      } else {
        // Rays cross the x rows: walk the rows of this image row from the
        // camera side, taking the bits not yet found, until every column has
        // its voxel or the volume ends.
        std::fill(found.begin(), found.end(), 0);
        std::int64_t remaining = nx;
        for (std::int64_t s = 0; s < n_depth && remaining > 0; ++s) {
          const std::int64_t d = view.from_positive ? n_depth - 1 - s : s;
          const std::int64_t j = view.axis == 2 ? u : d, k = view.axis == 2 ? d : u;
          const std::uint64_t* row = volume.row(j, k);
          for (std::int64_t w = 0; w < words; ++w) {
            std::uint64_t fresh = row[w] & ~found[static_cast<std::size_t>(w)];
            if (!fresh) continue;
            found[static_cast<std::size_t>(w)] |= fresh;
            remaining -= std::popcount(fresh);
            for (; fresh; fresh &= fresh - 1) {
              const std::int64_t i = w * 64 + std::countr_zero(fresh);
              const std::int64_t c = along_right(i);
              voxel[c] = i + nx * (j + ny * k);
              dist[c] = static_cast<std::int32_t>(s);
            }
          }
        }
      }
      for (std::int64_t c = 0; c < width; ++c) {
        if (voxel[c] < 0) continue;
        const std::int64_t v = voxel[c];
        raw[static_cast<std::size_t>(r * width + c)] =
            neighbour_normal(volume, v % nx, (v / nx) % ny, v / (nx * ny), -forward);
      }
    }
  });

  std::int32_t nearest = std::numeric_limits<std::int32_t>::max(), farthest = -1;
  for (const std::int32_t d : depth) {
    if (d < 0) continue;
    nearest = std::min(nearest, d);
    farthest = std::max(farthest, d);
  }
  if (farthest < 0) return img;  // nothing visible
  const float depth_span = static_cast<float>(farthest - nearest);

  const glm::vec3 light = glm::normalize(-forward + 0.5f * up - 0.35f * right);
  parallel_for(0, img.height, 8, threads, [&](std::int64_t r0, std::int64_t r1) {
    for (std::int64_t r = r0; r < r1; ++r) {
      for (std::int64_t c = 0; c < width; ++c) {
        const std::size_t p = static_cast<std::size_t>(r * width + c);
        const std::int32_t d0 = depth[p];
        if (d0 < 0) continue;
        // Screen-space smoothing hides the voxel staircase; the depth test
        // keeps a silhouette from averaging with a surface far behind it.
        glm::vec3 sum(0.0f);
        for (std::int64_t rr = std::max<std::int64_t>(r - 1, 0); rr <= std::min<std::int64_t>(r + 1, img.height - 1); ++rr) {
          for (std::int64_t cc = std::max<std::int64_t>(c - 1, 0); cc <= std::min<std::int64_t>(c + 1, width - 1); ++cc) {
            const std::size_t q = static_cast<std::size_t>(rr * width + cc);
            if (depth[q] >= 0 && std::abs(depth[q] - d0) <= 2) sum += raw[q];
          }
        }
        const float len = glm::length(sum);
        const glm::vec3 n = len < 1e-4f ? raw[p] : sum / len;
        const float t = depth_span > 0.0f ? static_cast<float>(d0 - nearest) / depth_span : 0.0f;
        const float shade = (0.2f + 0.8f * std::max(0.0f, glm::dot(n, light))) * (1.0f - 0.2f * t);
        img.normal[p] = n;
        img.shade[p] = std::clamp(shade, 0.0f, 1.0f);
      }
    }
  });
  return img;
}

}  // namespace voxd
