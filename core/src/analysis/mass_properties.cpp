#include "voxd/analysis/mass_properties.h"

#include <cstdint>
#include <algorithm>
#include <bit>
#include <mutex>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "analysis/row_runs.h"
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

namespace {

using Int128 = __int128;

// Exact integer moments of filled voxel indices (i, j, k): counts and sums of
// i, j, k and of their products, per row in closed form over runs.
struct IndexMoments {
  Int128 n = 0, si = 0, sj = 0, sk = 0, sii = 0, sjj = 0, skk = 0, sij = 0, sjk = 0, sik = 0;
  glm::i64vec3 lo{INT64_MAX}, hi{-1};

  IndexMoments& operator+=(const IndexMoments& o) {
    n += o.n, si += o.si, sj += o.sj, sk += o.sk, sii += o.sii, sjj += o.sjj, skk += o.skk;
    sij += o.sij, sjk += o.sjk, sik += o.sik;
    lo = glm::min(lo, o.lo);
    hi = glm::max(hi, o.hi);
    return *this;
  }
};

// Σ i² for i in [0, m).
inline std::int64_t squares_below(std::int64_t m) { return (m - 1) * m * (2 * m - 1) / 6; }

// Adds row (j, k), whose filled runs [begin, end) along x `for_each_run`
// hands to its callback in order.
template <class ForEachRun>
void add_row(const ForEachRun& for_each_run, std::int64_t j, std::int64_t k, IndexMoments& s) {
  std::int64_t n = 0, si = 0, sii = 0, first = -1, last = -1;
  for_each_run([&](std::int64_t begin, std::int64_t end) {
    if (first < 0) first = begin;
    n += end - begin;
    si += (begin + end - 1) * (end - begin) / 2;
    sii += squares_below(end) - squares_below(begin);
    last = end - 1;
  });
  if (n == 0) return;
  s.n += n;
  s.si += si;
  s.sj += Int128{n} * j;
  s.sk += Int128{n} * k;
  s.sii += sii;
  s.sjj += Int128{n} * j * j;
  s.skk += Int128{n} * k * k;
  s.sij += Int128{si} * j;
  s.sjk += Int128{n} * j * k;
  s.sik += Int128{si} * k;
  s.lo = glm::min(s.lo, glm::i64vec3(first, j, k));
  s.hi = glm::max(s.hi, glm::i64vec3(last, j, k));
}

// (n Σab − Σa Σb) / n: the central second moment, exact until the division.
double central(Int128 n, Int128 sab, Int128 sa, Int128 sb) {
  return static_cast<double>(n * sab - sa * sb) / static_cast<double>(n);
}

}  // namespace

struct VoxelMassAccumulator::Sums : IndexMoments {};

VoxelMassAccumulator::VoxelMassAccumulator(const Grid& grid) : grid_(grid), sums_(std::make_unique<Sums>()) {}
VoxelMassAccumulator::~VoxelMassAccumulator() = default;

void VoxelMassAccumulator::add(std::int64_t k0, const BitVolume& slab, int threads) {
  std::mutex total_mutex;
  const std::int64_t nx = slab.grid().dims.x, words = slab.row_words();
  parallel_for(0, slab.grid().dims.z, 4, threads, [&](std::int64_t a, std::int64_t b) {
    IndexMoments s;
    for (std::int64_t k = a; k < b; ++k)
      for (std::int64_t j = 0; j < slab.grid().dims.y; ++j) {
        const std::uint64_t* row = slab.row(j, k);
        add_row([&](const auto& on_run) { detail::for_each_row_run(row, words, nx, false, on_run); }, j, k0 + k, s);
      }
    std::lock_guard lock(total_mutex);
    *sums_ += s;  // integers: the total does not depend on the order
  });
}

void VoxelMassAccumulator::add(std::int64_t k0, const RunSlab& slab, int threads) {
  std::mutex total_mutex;
  parallel_for(0, slab.grid().dims.z, 4, threads, [&](std::int64_t a, std::int64_t b) {
    IndexMoments s;
    for (std::int64_t k = a; k < b; ++k)
      for (std::int64_t j = 0; j < slab.grid().dims.y; ++j) {
        const auto runs = slab.row(j, k);
        add_row([&](const auto& on_run) {
          for (std::size_t r = 0; r < runs.size(); r += 2) on_run(std::int64_t{runs[r]}, std::int64_t{runs[r + 1]});
        }, j, k0 + k, s);
      }
    std::lock_guard lock(total_mutex);
    *sums_ += s;
  });
}

MassProperties VoxelMassAccumulator::result() const {
  const IndexMoments& s = *sums_;
  MassProperties p;
  if (s.n == 0) return p;
  const double h = grid_.voxel_size, n = static_cast<double>(s.n);
  p.volume = n * h * h * h;
  const glm::dvec3 mean{static_cast<double>(s.si) / n, static_cast<double>(s.sj) / n, static_cast<double>(s.sk) / n};
  p.centroid = grid_.origin + (mean + glm::dvec3(0.5)) * h;
  // Each voxel is a unit cube, not a point: its own ∫x² about its centre is 1/12.
  const double own = n / 12.0;
  const double xx = central(s.n, s.sii, s.si, s.si) + own, yy = central(s.n, s.sjj, s.sj, s.sj) + own,
               zz = central(s.n, s.skk, s.sk, s.sk) + own;
  const double xy = central(s.n, s.sij, s.si, s.sj), yz = central(s.n, s.sjk, s.sj, s.sk), zx = central(s.n, s.sik, s.si, s.sk);
  const double h5 = h * h * h * h * h;
  p.inertia = h5 * glm::dmat3(yy + zz, -xy, -zx,  //
                              -xy, xx + zz, -yz,  //
                              -zx, -yz, xx + yy);
  p.bbox.min = grid_.origin + glm::dvec3(s.lo) * h;
  p.bbox.max = grid_.origin + glm::dvec3(s.hi + glm::i64vec3(1)) * h;
  return p;
}

MassProperties voxel_mass_properties(const BitVolume& volume, int threads) {
  VoxelMassAccumulator sums(volume.grid());
  sums.add(0, volume, threads);
  return sums.result();
}

}  // namespace voxd
