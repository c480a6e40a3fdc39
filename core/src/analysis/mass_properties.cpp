#include "voxd/analysis/mass_properties.h"

#include <algorithm>
#include <bit>
#include <mutex>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "voxd/parallel.h"

namespace voxd {
namespace {

// Volume integrals ∫1, ∫x, ∫y, ∫z, ∫x², ∫y², ∫z², ∫xy, ∫yz, ∫zx.
struct Moments {
  double m[10] = {};
  Moments& operator+=(const Moments& o) {
    for (int i = 0; i < 10; ++i) m[i] += o.m[i];
    return *this;
  }
};

// Central quantities from raw moments taken about `ref` (moments were
// accumulated in coordinates relative to ref, to keep the sums small).
MassProperties from_moments(const Moments& s, glm::dvec3 ref) {
  MassProperties p;
  p.volume = s.m[0];
  if (s.m[0] == 0.0) return p;
  const glm::dvec3 c{s.m[1] / s.m[0], s.m[2] / s.m[0], s.m[3] / s.m[0]};
  p.centroid = ref + c;
  // Second moments about the centroid (parallel-axis shift).
  const double xx = s.m[4] - s.m[0] * c.x * c.x, yy = s.m[5] - s.m[0] * c.y * c.y, zz = s.m[6] - s.m[0] * c.z * c.z;
  const double xy = s.m[7] - s.m[0] * c.x * c.y, yz = s.m[8] - s.m[0] * c.y * c.z, zx = s.m[9] - s.m[0] * c.z * c.x;
  p.inertia = glm::dmat3(yy + zz, -xy, -zx,  //
                         -xy, xx + zz, -yz,  //
                         -zx, -yz, xx + yy);
  return p;
}

}  // namespace

MassProperties mesh_mass_properties(const Mesh& mesh) {
  const Aabb box = bounds(mesh);
  const glm::dvec3 ref = box.center();
  Moments s;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    // Tetrahedron (ref, a, b, c); its integrals in closed form (Tonon 2004).
    const glm::dvec3 a = glm::dvec3(mesh.corner(t, 0)) - ref;
    const glm::dvec3 b = glm::dvec3(mesh.corner(t, 1)) - ref;
    const glm::dvec3 c = glm::dvec3(mesh.corner(t, 2)) - ref;
    const double det = glm::dot(a, glm::cross(b, c));
    const double v = det / 6.0;
    s.m[0] += v;
    for (int i = 0; i < 3; ++i) s.m[1 + i] += v * (a[i] + b[i] + c[i]) / 4.0;
    for (int i = 0; i < 3; ++i)
      s.m[4 + i] += det / 60.0 * (a[i] * a[i] + b[i] * b[i] + c[i] * c[i] + a[i] * b[i] + a[i] * c[i] + b[i] * c[i]);
    const int pairs[3][2] = {{0, 1}, {1, 2}, {2, 0}};
    for (int q = 0; q < 3; ++q) {
      const int i = pairs[q][0], j = pairs[q][1];
      s.m[7 + q] += det / 120.0 *
                    (2 * a[i] * a[j] + 2 * b[i] * b[j] + 2 * c[i] * c[j] + a[i] * b[j] + a[j] * b[i] + a[i] * c[j] +
                     a[j] * c[i] + b[i] * c[j] + b[j] * c[i]);
    }
  }
  MassProperties p = from_moments(s, ref);
  p.bbox = box;
  return p;
}

MassProperties voxel_mass_properties(const BitVolume& volume, int threads) {
  const Grid& g = volume.grid();
  const double h = g.voxel_size;
  // Sums in voxel index units about the grid centre, converted at the end.
  const glm::dvec3 mid = glm::dvec3(g.dims) * 0.5;
  Moments total;
  std::mutex total_mutex;
  glm::i64vec3 lo(g.dims), hi(-1);
  parallel_for(0, g.dims.z, 4, threads, [&](std::int64_t k0, std::int64_t k1) {
    Moments s;
    glm::i64vec3 my_lo(g.dims), my_hi(-1);
    for (std::int64_t k = k0; k < k1; ++k) {
      const double z = static_cast<double>(k) + 0.5 - mid.z;
      for (std::int64_t j = 0; j < g.dims.y; ++j) {
        const std::uint64_t* row = volume.row(j, k);
        // Per row: count, Σx, Σx² of the filled centres; y and z are constant.
        double n = 0, sx = 0, sxx = 0;
        std::int64_t first = -1, last = -1;
        for (std::int64_t w = 0; w < volume.row_words(); ++w) {
          std::uint64_t bits = row[w];
          if (!bits) continue;
          if (first < 0) first = w * 64 + std::countr_zero(bits);
          last = w * 64 + 63 - std::countl_zero(bits);
          while (bits) {
            const double x = static_cast<double>(w * 64 + std::countr_zero(bits)) + 0.5 - mid.x;
            n += 1;
            sx += x;
            sxx += x * x;
            bits &= bits - 1;
          }
        }
        if (n == 0) continue;
        const double y = static_cast<double>(j) + 0.5 - mid.y;
        s.m[0] += n;
        s.m[1] += sx;
        s.m[2] += n * y;
        s.m[3] += n * z;
        s.m[4] += sxx;
        s.m[5] += n * y * y;
        s.m[6] += n * z * z;
        s.m[7] += sx * y;
        s.m[8] += n * y * z;
        s.m[9] += sx * z;
        my_lo = glm::min(my_lo, glm::i64vec3(first, j, k));
        my_hi = glm::max(my_hi, glm::i64vec3(last, j, k));
      }
    }
    std::lock_guard lock(total_mutex);
    total += s;
    lo = glm::min(lo, my_lo);
    hi = glm::max(hi, my_hi);
  });
  // Each voxel is a unit cube, not a point: its own ∫x² about its centre is 1/12.
  for (int i = 4; i < 7; ++i) total.m[i] += total.m[0] / 12.0;
  // Scale index units to model units: ∫1 by h³, first moments by h⁴, second by h⁵.
  const double h3 = h * h * h;
  for (int i = 0; i < 10; ++i) total.m[i] *= i == 0 ? h3 : i < 4 ? h3 * h : h3 * h * h;
  MassProperties p = from_moments(total, g.origin + mid * h);
  if (hi.x >= 0) {
    p.bbox.min = g.origin + glm::dvec3(lo) * h;
    p.bbox.max = g.origin + glm::dvec3(hi + glm::i64vec3(1)) * h;
  }
  return p;
}

}  // namespace voxd
