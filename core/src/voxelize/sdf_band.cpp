// The narrow band by scattering triangles to voxels; see sdf_band.h.
#include "voxelize/sdf_band.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <limits>
#include <vector>

#include <glm/geometric.hpp>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

#include "voxd/parallel.h"
#include "voxelize/sdf_triangle.h"

// Loops over a cluster's lanes, cloned for AVX-512 and AVX2 and chosen at
// load time by the CPU (GCC's function multiversioning); the portable build
// targets x86-64-v2, which has neither.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define VOXD_VECTOR_CLONES __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define VOXD_VECTOR_CLONES
#endif

namespace voxd::sdf {
namespace {

inline dvec3 corner(const Mesh& mesh, std::size_t tri, int c) { return dvec3(mesh.corner(tri, c)); }

// Lowers each voxel of slabs [z0, z1) within the band of triangle t to its
// distance if that is smaller. `values` hold float(distance * to_output);
// the minimum of rounded values is the rounded minimum, so the order in which
// triangles arrive does not matter.
//
// Which voxels to visit is worked out per row in index space (voxel i's
// centre at coordinate i), cheap and with a margin for rounding: the band of
// the bounding box, of the bounding sphere and of the plane. Each visited
// voxel then gets two lower bounds in model units, relative to the triangle
// (so small numbers, small rounding): its distance to the plane and to the
// bounding sphere. If either reaches its current value the triangle cannot
// lower it; only then is the exact distance computed. Once the nearer
// triangles have been by, the sphere skips most voxels (the plane alone does
// not: along a curved surface the neighbours' planes pass close to a voxel).
//
// Out of line: inlined into scatter_band_chunk (as GCC chose once the
// triangle became a template) it ran 3.7% more instructions at 128^3.
[[gnu::noinline]] void scatter_triangle(const Triangle& t, const Grid& g, const BandSetup& s, std::int64_t z0, std::int64_t z1,
                      DenseVolume<float>& values, std::int64_t z_origin) {
  const IndexSpace index_of(g);
  const double band = s.band * index_of.inv_voxel, band2 = band * band;  // voxels
  const dvec3 lo = index_of(glm::min(glm::min(t.a, t.b), t.c)), hi = index_of(glm::max(glm::max(t.a, t.b), t.c));
  const dvec3 centroid = (t.a + t.b + t.c) / 3.0;
  const double radius =
      std::sqrt(std::max({glm::dot(t.a - centroid, t.a - centroid), glm::dot(t.b - centroid, t.b - centroid),
                          glm::dot(t.c - centroid, t.c - centroid)})) * (1.0 + 1e-9);
  const dvec3 centroid_i = index_of(centroid);
  const double reach = band + radius * index_of.inv_voxel, reach2 = reach * reach;
  const dvec3 unit = t.degenerate ? dvec3(0.0) : t.n / std::sqrt(t.nn);
  const dvec3 a_i = index_of(t.a);
  // Restrict rows by the plane only where that is well conditioned.
  const double inv_unit_x = std::abs(unit.x) > 1e-3 ? 1.0 / unit.x : 0.0;

  const std::int64_t k0 = std::max(z0, IndexSpace::first(lo.z - band, g.dims.z));
  const std::int64_t k1 = std::min(z1 - 1, IndexSpace::last(hi.z + band, g.dims.z));
  const std::int64_t j0 = IndexSpace::first(lo.y - band, g.dims.y), j1 = IndexSpace::last(hi.y + band, g.dims.y);
  for (std::int64_t k = k0; k <= k1; ++k) {
    const auto kk = static_cast<double>(k);
    const double dz = std::max({lo.z - kk, kk - hi.z, 0.0}), sz = kk - centroid_i.z;
    const double cz = centre_coordinate(g, 2, k);
    float* slab = values.slab(k - z_origin);
    for (std::int64_t j = j0; j <= j1; ++j) {
      const auto jj = static_cast<double>(j);
      const double dy = std::max({lo.y - jj, jj - hi.y, 0.0}), sy = jj - centroid_i.y;
      const double box_rest2 = band2 - dy * dy - dz * dz, sphere_rest2 = reach2 - sy * sy - sz * sz;
      if (box_rest2 < 0.0 || sphere_rest2 < 0.0) continue;
      const double bx = std::sqrt(box_rest2), sx = std::sqrt(sphere_rest2);
      double from = std::max(lo.x - bx, centroid_i.x - sx), to = std::min(hi.x + bx, centroid_i.x + sx);
      const double plane_yz_i = unit.y * (jj - a_i.y) + unit.z * (kk - a_i.z);
      if (inv_unit_x != 0.0) {  // |plane_yz_i + unit.x (i - a_i.x)| <= band
        const double p0 = a_i.x + (-band - plane_yz_i) * inv_unit_x, p1 = a_i.x + (band - plane_yz_i) * inv_unit_x;
        from = std::max(from, std::min(p0, p1));
        to = std::min(to, std::max(p0, p1));
      }
      const std::int64_t i0 = IndexSpace::first(from, g.dims.x), i1 = IndexSpace::last(to, g.dims.x);

      const double cy = centre_coordinate(g, 1, j);
      const double plane_yz = unit.y * (cy - t.a.y) + unit.z * (cz - t.a.z);
      const double sphere_yz2 = (cy - centroid.y) * (cy - centroid.y) + (cz - centroid.z) * (cz - centroid.z);
      float* row = slab + j * g.dims.x;
      for (std::int64_t i = i0; i <= i1; ++i) {
        const double cx = centre_coordinate(g, 0, i);
        const double limit = static_cast<double>(row[i]) * s.to_model;
        const double plane = plane_yz + unit.x * (cx - t.a.x);
        if (plane * plane >= limit * limit) continue;
        const double sphere2 = (cx - centroid.x) * (cx - centroid.x) + sphere_yz2;
        if (sphere2 >= (limit + radius) * (limit + radius)) continue;
        const double d2 = distance2(t, dvec3(cx, cy, cz));
        if (d2 >= limit * limit) continue;
        row[i] = std::min(row[i], static_cast<float>(std::sqrt(d2) * s.to_output));
      }
    }
  }
}

// ---------------------------------------------------------------------------
// Clusters: scattering triangle by triangle visits each band voxel once per
// triangle within the band of it (about 50 at 512^3 on the benchmark mesh,
// each visit a few bound tests), since the band (3 voxels) is wide against
// the triangles. Neighbouring triangles are grouped instead, and a cluster
// visits the band of its box once; per voxel, one bound on the whole cluster
// (an oriented box, thin along a smooth patch) settles most visits, and only
// where it may beat the voxel's value are the cluster's triangles tested one
// by one, as before. Grouping: triangles whose centroids share a cell of a
// coarse grid, sized for about 40 triangles per cell on a smooth
// surface, at most kClusterSize per cluster.

// Sorts `keys` on `threads` threads: blocks sorted in parallel, then merged.
void parallel_sort(std::vector<std::uint64_t>& keys, int threads) {
  const auto n = static_cast<std::int64_t>(keys.size());
  const std::int64_t blocks = std::clamp<std::int64_t>(threads, 1, 64), size = (n + blocks - 1) / blocks;
  if (blocks == 1 || n < 65536) {
    std::sort(keys.begin(), keys.end());
    return;
  }
  parallel_for(0, blocks, 1, threads, [&](std::int64_t b0, std::int64_t b1) {
    for (std::int64_t b = b0; b < b1; ++b)
      std::sort(keys.begin() + std::min(n, b * size), keys.begin() + std::min(n, (b + 1) * size));
  });
  for (std::int64_t width = size; width < n; width *= 2)
    for (std::int64_t b = 0; b + width < n; b += 2 * width)
      std::inplace_merge(keys.begin() + b, keys.begin() + b + width, keys.begin() + std::min(n, b + 2 * width));
}

void fit_cluster(const Mesh& mesh, const std::vector<std::uint32_t>& order, const IndexSpace& index_of,
                 double voxel, Cluster& c) {
  dvec3 lo(kInfinity), hi(-kInfinity), area(0.0);
  for (std::uint32_t x = c.begin; x < c.end; ++x) {
    const dvec3 a = corner(mesh, order[x], 0), b = corner(mesh, order[x], 1), d = corner(mesh, order[x], 2);
    lo = glm::min(lo, glm::min(glm::min(a, b), d));
    hi = glm::max(hi, glm::max(glm::max(a, b), d));
    area += glm::cross(b - a, d - a);
  }
  c.lo = index_of(lo);
  c.hi = index_of(hi);
  const double area_length = glm::length(area);
  if (c.end - c.begin < 2 || !(area_length > 0.0) || !std::isfinite(area_length)) return;  // not flat
  c.n = area / area_length;
  dvec3 u(0.0);
  u[std::abs(c.n.x) < 0.6 ? 0 : 1] = 1.0;
  c.u = glm::normalize(u - glm::dot(u, c.n) * c.n);
  c.w = glm::cross(c.n, c.u);
  const dvec3 box_centre = 0.5 * (lo + hi);
  dvec3 qmin(kInfinity), qmax(-kInfinity);
  auto frame = [&](const dvec3& d) { return dvec3(glm::dot(c.u, d), glm::dot(c.w, d), glm::dot(c.n, d)); };
  for (std::uint32_t x = c.begin; x < c.end; ++x)
    for (int k = 0; k < 3; ++k) {
      const dvec3 q = frame(corner(mesh, order[x], k) - box_centre);
      qmin = glm::min(qmin, q);
      qmax = glm::max(qmax, q);
    }
  const dvec3 mid = 0.5 * (qmin + qmax);
  c.centre = box_centre + mid.x * c.u + mid.y * c.w + mid.z * c.n;
  dvec3 half(0.0);
  double r2 = 0.0;
  for (std::uint32_t x = c.begin; x < c.end; ++x)
    for (int k = 0; k < 3; ++k) {
      const dvec3 d = corner(mesh, order[x], k) - c.centre;
      half = glm::max(half, glm::abs(frame(d)));
      r2 = std::max(r2, glm::dot(d, d));
    }
  // The box holds every vertex, so (convex) every triangle; the slack
  // covers the rounding of the frame products, far below a millionth.
  const double slack = 1e-9 * (glm::length(hi - lo) + glm::length(c.centre));
  c.half = half + slack;
  c.radius = std::sqrt(r2) * (1.0 + 1e-9) + slack;
  // Thin against a voxel: the band of the box is then about the band of the
  // patch. A thick or folded group is cheaper triangle by triangle.
  c.flat = c.half.z <= 0.5 * voxel;
}

ClusterSet make_clusters(const Mesh& mesh, const Grid& g, int threads) {
  ClusterSet set;
  const std::size_t n = mesh.triangle_count();
  if (n == 0) return set;
  const IndexSpace index_of(g);
  // The mean triangle area (voxels^2) from a sample: it only sizes cells.
  const std::size_t stride = std::max<std::size_t>(1, n / 65536);
  double area = 0.0;
  std::size_t sampled = 0;
  for (std::size_t t = 0; t < n; t += stride, ++sampled) {
    const dvec3 a = corner(mesh, t, 0), b = corner(mesh, t, 1), c = corner(mesh, t, 2);
    area += 0.5 * glm::length(glm::cross(b - a, c - a));
  }
  area *= index_of.inv_voxel * index_of.inv_voxel * static_cast<double>(n) / static_cast<double>(sampled);
  // A plane crosses a cube of side s in about 1.2 s^2 on average: about 40
  // triangles per cell; never below a voxel. Larger cells mean fewer, larger
  // clusters: each band voxel meets fewer of them (the band around a cluster
  // grows slower than its patch), while the per-voxel work inside one is
  // vector code over its lanes. Measured at 512^3 (sdf_bench): 16 triangles
  // and cells for 10, 1.53 s; 32 and 28, 1.09-1.26 s; 64 and 40, 1.11-1.20 s,
  // and the best at 256^3.
  double cell = std::clamp(std::sqrt(40.0 * area / static_cast<double>(n)), 1.0, 64.0);
  if (!std::isfinite(cell)) cell = 1.0;
  auto cells = [&](int axis) { return static_cast<std::uint64_t>(std::ceil(static_cast<double>(g.dims[axis]) / cell)) + 2; };
  while (cells(0) * cells(1) * cells(2) >= (std::uint64_t{1} << 31)) cell *= 2.0;
  const std::uint64_t ncx = cells(0), ncy = cells(1), ncz = cells(2);
  std::vector<std::uint64_t> keys(n);
  parallel_for(0, static_cast<std::int64_t>(n), 65536, threads, [&](std::int64_t t0, std::int64_t t1) {
    for (std::int64_t t = t0; t < t1; ++t) {
      const auto tt = static_cast<std::size_t>(t);
      const dvec3 centroid = index_of((corner(mesh, tt, 0) + corner(mesh, tt, 1) + corner(mesh, tt, 2)) / 3.0);
      auto cell_of = [&](double x, std::uint64_t count) {
        const double c = std::floor(x / cell) + 1.0;
        return static_cast<std::uint64_t>(std::clamp(std::isfinite(c) ? c : 0.0, 0.0, static_cast<double>(count - 1)));
      };
      // z fastest: a chunk (a few z-cells thick) then takes its clusters
      // column by column, and the voxels they share stay in cache.
      const std::uint64_t key =
          (cell_of(centroid.y, ncy) * ncx + cell_of(centroid.x, ncx)) * ncz + cell_of(centroid.z, ncz);
      keys[tt] = key << 32 | static_cast<std::uint64_t>(t);
    }
  });
  parallel_sort(keys, threads);
  set.order.resize(n);
  for (std::size_t x = 0; x < n;) {
    std::size_t end = x + 1;
    while (end < n && end - x < kClusterSize && keys[end] >> 32 == keys[x] >> 32) ++end;
    Cluster c;
    c.begin = static_cast<std::uint32_t>(x);
    c.end = static_cast<std::uint32_t>(end);
    set.clusters.push_back(c);
    x = end;
  }
  for (std::size_t x = 0; x < n; ++x) set.order[x] = static_cast<std::uint32_t>(keys[x]);
  parallel_for(0, static_cast<std::int64_t>(set.clusters.size()), 4096, threads, [&](std::int64_t c0, std::int64_t c1) {
    for (std::int64_t c = c0; c < c1; ++c)
      fit_cluster(mesh, set.order, index_of, g.voxel_size, set.clusters[static_cast<std::size_t>(c)]);
  });
  return set;
}

// The float at or above v (v >= 0 and finite: the next float up is the
// next bit pattern).
inline float round_up(double v) {
  const auto f = static_cast<float>(v);
  return static_cast<double>(f) >= v ? f : std::bit_cast<float>(std::bit_cast<std::uint32_t>(f) + 1u);
}

// A cluster's triangles as structure of arrays: the lower bounds of one
// voxel against all of them are then one straight loop the compiler turns
// into vector code (lower_bounds), where an array of triangle structs kept it
// scalar. Lanes past `count` hold zeros; their bounds are ignored.
}  // namespace

// Named outside the anonymous namespace: BandScratch (sdf_band.h) holds one.
struct ProbeBlock {
  std::size_t count = 0;
  std::vector<Triangle> triangles;  // for the exact distances
  alignas(64) double ax[kClusterSize], ay[kClusterSize], az[kClusterSize];
  double ux[kClusterSize], uy[kClusterSize], uz[kClusterSize];  // unit normal; 0 when degenerate
  // In-plane edge normals divided by their length (0 when degenerate), and
  // the edges' start vertices b and c (a is above).
  double abx[kClusterSize], aby[kClusterSize], abz[kClusterSize];
  double bx[kClusterSize], by[kClusterSize], bz[kClusterSize], bcx[kClusterSize], bcy[kClusterSize], bcz[kClusterSize];
  double cx[kClusterSize], cy[kClusterSize], cz[kClusterSize], cax[kClusterSize], cay[kClusterSize], caz[kClusterSize];
  // Centroids, for the seeding pass's upper bounds (infinite in unused lanes).
  double gx[kClusterSize], gy[kClusterSize], gz[kClusterSize];

  ProbeBlock() { clear(); }
  void clear() {
    count = 0;
    triangles.clear();
    for (double* v : {ax, ay, az, ux, uy, uz, abx, aby, abz, bx, by, bz, bcx, bcy, bcz, cx, cy, cz, cax, cay, caz})
      std::fill(v, v + kClusterSize, 0.0);
    for (double* v : {gx, gy, gz}) std::fill(v, v + kClusterSize, kInfinity);
  }
  // The seeding pass needs the centroids only.
  void add_centroid(const dvec3& g) {
    const std::size_t x = count++;
    gx[x] = g.x, gy[x] = g.y, gz[x] = g.z;
  }
  void add(const Triangle& t) {
    const std::size_t x = count++;
    triangles.push_back(t);
    ax[x] = t.a.x, ay[x] = t.a.y, az[x] = t.a.z;
    bx[x] = t.b.x, by[x] = t.b.y, bz[x] = t.b.z;
    cx[x] = t.c.x, cy[x] = t.c.y, cz[x] = t.c.z;
    const dvec3 g = (t.a + t.b + t.c) / 3.0;
    gx[x] = g.x, gy[x] = g.y, gz[x] = g.z;
    if (t.degenerate) return;  // bound 0: always tested exactly
    const dvec3 u = t.n / std::sqrt(t.nn);
    const dvec3 iab = t.in_ab / glm::length(t.in_ab), ibc = t.in_bc / glm::length(t.in_bc),
                ica = t.in_ca / glm::length(t.in_ca);
    ux[x] = u.x, uy[x] = u.y, uz[x] = u.z;
    abx[x] = iab.x, aby[x] = iab.y, abz[x] = iab.z;
    bcx[x] = ibc.x, bcy[x] = ibc.y, bcz[x] = ibc.z;
    cax[x] = ica.x, cay[x] = ica.y, caz[x] = ica.z;
  }
};

namespace {

// Lower bounds of distance2(triangle, p) for every lane, without branches or
// divisions: the point's height over the plane and, in the plane, how far
// its projection lies outside the farthest edge line (the distance to that
// half-plane, which holds the triangle). The factor and the term in |ap|^2
// cover the rounding (relative 1e-15 of |ap|; also with fused multiply-adds),
// far below a float's resolution. Degenerate lanes give a bound <= 0.
// Vector clones (VOXD_VECTOR_CLONES); the exact distances stay in the
// baseline code, so their bits do not depend on the machine.
VOXD_VECTOR_CLONES void lower_bounds(const ProbeBlock& q, double px, double py, double pz, double* out) {
  for (std::size_t x = 0; x < kClusterSize; ++x) {
    const double apx = px - q.ax[x], apy = py - q.ay[x], apz = pz - q.az[x];
    const double bpx = px - q.bx[x], bpy = py - q.by[x], bpz = pz - q.bz[x];
    const double cpx = px - q.cx[x], cpy = py - q.cy[x], cpz = pz - q.cz[x];
    const double h = q.ux[x] * apx + q.uy[x] * apy + q.uz[x] * apz;
    const double e1 = -(q.abx[x] * apx + q.aby[x] * apy + q.abz[x] * apz);
    const double e2 = -(q.bcx[x] * bpx + q.bcy[x] * bpy + q.bcz[x] * bpz);
    const double e3 = -(q.cax[x] * cpx + q.cay[x] * cpy + q.caz[x] * cpz);
    double e = e1 > 0.0 ? e1 : 0.0;
    e = e2 > e ? e2 : e;
    e = e3 > e ? e3 : e;
    out[x] = (h * h + e * e) * (1.0 - 1e-9) - 1e-12 * (apx * apx + apy * apy + apz * apz);
  }
}

// The squared distance from p to the nearest lane's centroid (lanes past
// `count` hold infinite centroids), the minimum taken pairwise so that it
// stays vector code.
VOXD_VECTOR_CLONES double nearest_centroid2(const ProbeBlock& q, double px, double py, double pz) {
  double d[kClusterSize];
  for (std::size_t x = 0; x < kClusterSize; ++x) {
    const double dx = px - q.gx[x], dy = py - q.gy[x], dz = pz - q.gz[x];
    d[x] = dx * dx + dy * dy + dz * dz;
  }
  for (std::size_t width = kClusterSize / 2; width > 0; width /= 2)
    for (std::size_t x = 0; x < width; ++x) d[x] = d[x + width] < d[x] ? d[x + width] : d[x];
  return d[0];
}

// The per-voxel test of a row against a cluster's oriented box, the bulk of
// the band's work (each band voxel meets a few dozen clusters, nearly all of
// which this test turns away). Rows are short (the band's width and a
// cluster's), too short for the compiler's vector loops, so the AVX2 form
// takes four voxels at a time with a masked tail. Both forms set bit m of
// `mask` when voxel i0 + m of row[i0, i0 + n) may be lowered by the cluster:
// its distance to the box, a lower bound of every triangle's (to rounding far
// below a float's resolution, which the factor covers), is below its value.
struct RowBox {
  double origin_x, voxel;   // centre of voxel i: origin_x + (i + 1/2) voxel
  double centre_x;          // the box's centre
  double u_yz, w_yz, n_yz;  // the row's y, z part of the box frame coordinates
  double ux, wx, nx;        // the frame axes' x components
  double hu, hw, hn;        // half-extents
  double to_model;
};

void box_mask_scalar(const RowBox& b, const float* row, std::int64_t i0, std::int64_t n, std::uint64_t* mask) {
  for (std::int64_t m = 0; m < n; ++m) {
    const double ex = b.origin_x + (static_cast<double>(i0 + m) + 0.5) * b.voxel - b.centre_x;
    const double limit = static_cast<double>(row[m]) * b.to_model;
    const double qu = std::max(std::abs(b.u_yz + b.ux * ex) - b.hu, 0.0);
    const double qw = std::max(std::abs(b.w_yz + b.wx * ex) - b.hw, 0.0);
    const double qn = std::max(std::abs(b.n_yz + b.nx * ex) - b.hn, 0.0);
    if ((qu * qu + qw * qw + qn * qn) * (1.0 - 1e-9) < limit * limit) mask[m >> 6] |= std::uint64_t{1} << (m & 63);
  }
}

#if defined(__x86_64__) && defined(__GNUC__)
__attribute__((target("avx2,fma"))) void box_mask_avx2(const RowBox& b, const float* row, std::int64_t i0,
                                                        std::int64_t n, std::uint64_t* mask) {
  const __m256d voxel = _mm256_set1_pd(b.voxel), origin = _mm256_set1_pd(b.origin_x), centre = _mm256_set1_pd(b.centre_x);
  const __m256d u_yz = _mm256_set1_pd(b.u_yz), w_yz = _mm256_set1_pd(b.w_yz), n_yz = _mm256_set1_pd(b.n_yz);
  const __m256d ux = _mm256_set1_pd(b.ux), wx = _mm256_set1_pd(b.wx), nx = _mm256_set1_pd(b.nx);
  const __m256d hu = _mm256_set1_pd(b.hu), hw = _mm256_set1_pd(b.hw), hn = _mm256_set1_pd(b.hn);
  const __m256d to_model = _mm256_set1_pd(b.to_model), shrink = _mm256_set1_pd(1.0 - 1e-9);
  const __m256d zero = _mm256_setzero_pd(), sign = _mm256_set1_pd(-0.0), lane = _mm256_setr_pd(0.0, 1.0, 2.0, 3.0);
  const __m128i lane_index = _mm_setr_epi32(0, 1, 2, 3);
  for (std::int64_t m = 0; m < n; m += 4) {
    // Lanes past the row's end read nothing (their limit is 0: never pass).
    const __m128i in_row = _mm_cmpgt_epi32(_mm_set1_epi32(static_cast<int>(std::min<std::int64_t>(n - m, 4))), lane_index);
    const __m256d limit = _mm256_mul_pd(_mm256_cvtps_pd(_mm_maskload_ps(row + m, in_row)), to_model);
    const __m256d index = _mm256_add_pd(_mm256_set1_pd(static_cast<double>(i0 + m) + 0.5), lane);
    const __m256d ex = _mm256_sub_pd(_mm256_add_pd(origin, _mm256_mul_pd(index, voxel)), centre);
    const __m256d au = _mm256_andnot_pd(sign, _mm256_add_pd(u_yz, _mm256_mul_pd(ux, ex)));
    const __m256d aw = _mm256_andnot_pd(sign, _mm256_add_pd(w_yz, _mm256_mul_pd(wx, ex)));
    const __m256d an = _mm256_andnot_pd(sign, _mm256_add_pd(n_yz, _mm256_mul_pd(nx, ex)));
    const __m256d qu = _mm256_max_pd(_mm256_sub_pd(au, hu), zero);
    const __m256d qw = _mm256_max_pd(_mm256_sub_pd(aw, hw), zero);
    const __m256d qn = _mm256_max_pd(_mm256_sub_pd(an, hn), zero);
    const __m256d q2 = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(qu, qu), _mm256_mul_pd(qw, qw)), _mm256_mul_pd(qn, qn));
    const __m256d pass = _mm256_cmp_pd(_mm256_mul_pd(q2, shrink), _mm256_mul_pd(limit, limit), _CMP_LT_OQ);
    const auto bits = static_cast<std::uint64_t>(_mm256_movemask_pd(pass));
    mask[m >> 6] |= bits << (m & 63);  // m is a multiple of 4: the 4 bits stay in one word
  }
}
#endif

void box_mask(const RowBox& b, const float* row, std::int64_t i0, std::int64_t n, std::uint64_t* mask) {
#if defined(__x86_64__) && defined(__GNUC__)
  static const bool avx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  if (avx2) return box_mask_avx2(b, row, i0, n, mask);
#endif
  box_mask_scalar(b, row, i0, n, mask);
}

// Lowers each voxel of slabs [z0, z1) within the band of the flat cluster c
// to its distance to c's triangles if smaller, like scatter_triangle: rows
// restricted in index space by the band of the box, of the bounding sphere
// and of the slab along the mean normal; per voxel, the distance to the
// oriented box bounds all its triangles'.
template <bool kSeed>
void scatter_cluster(const Cluster& c, const ProbeBlock& probes, const Grid& g, const BandSetup& s, std::int64_t z0,
                     std::int64_t z1, DenseVolume<float>& values, std::int64_t z_origin, std::vector<std::uint64_t>& mask) {
  const IndexSpace index_of(g);
  const double band = s.band * index_of.inv_voxel;  // voxels
  const dvec3 centre_i = index_of(c.centre);
  // How far along x a voxel in the band can be from the centre.
  const double reach = band + c.radius * index_of.inv_voxel;
  // The band of the oriented box lies within three slabs, one along each
  // of its axes: |axis . (p - centre)| <= half + band.
  const std::array<dvec3, 3> axes{c.u, c.w, c.n};
  std::array<double, 3> slab{}, inv_x{};
  for (int a = 0; a < 3; ++a) {
    slab[a] = band + c.half[a] * index_of.inv_voxel;
    inv_x[a] = std::abs(axes[a].x) > 1e-3 ? 1.0 / axes[a].x : 0.0;
  }

  const std::int64_t k0 = std::max(z0, IndexSpace::first(c.lo.z - band, g.dims.z));
  const std::int64_t k1 = std::min(z1 - 1, IndexSpace::last(c.hi.z + band, g.dims.z));
  const std::int64_t j0 = IndexSpace::first(c.lo.y - band, g.dims.y), j1 = IndexSpace::last(c.hi.y + band, g.dims.y);
  for (std::int64_t k = k0; k <= k1; ++k) {
    const auto kk = static_cast<double>(k);
    std::array<double, 3> zpart{};
    for (int a = 0; a < 3; ++a) zpart[a] = axes[a].z * (kk - centre_i.z);
    const double cz = centre_coordinate(g, 2, k);
    float* slab_values = values.slab(k - z_origin);
    for (std::int64_t j = j0; j <= j1; ++j) {
      const auto jj = static_cast<double>(j);
      // The row within the band of the box's bounds and of its three slabs
      // (no roots: the voxel test below is exact, these only narrow it).
      double from = c.lo.x - band, to = c.hi.x + band;
      bool outside = false;
      for (int a = 0; a < 3; ++a) {
        const dvec3& e = axes[a];
        const double yz = e.y * (jj - centre_i.y) + zpart[a];
        if (inv_x[a] == 0.0) {  // the axis is nearly across the row: the whole row is in or out
          outside = outside || std::abs(yz) > slab[a] + std::abs(e.x) * reach;
          continue;
        }
        const double p0 = centre_i.x + (-slab[a] - yz) * inv_x[a], p1 = centre_i.x + (slab[a] - yz) * inv_x[a];
        from = std::max(from, std::min(p0, p1));
        to = std::min(to, std::max(p0, p1));
      }
      if (outside) continue;
      const std::int64_t i0 = IndexSpace::first(from, g.dims.x), i1 = IndexSpace::last(to, g.dims.x);
      if (i0 > i1) continue;

      const double cy = centre_coordinate(g, 1, j);
      const double ey = cy - c.centre.y, ez = cz - c.centre.z;
      const RowBox box{g.origin.x, g.voxel_size, c.centre.x, c.u.y * ey + c.u.z * ez, c.w.y * ey + c.w.z * ez,
                       c.n.y * ey + c.n.z * ez, c.u.x, c.w.x, c.n.x, c.half.x, c.half.y, c.half.z, s.to_model};
      float* row = slab_values + j * g.dims.x;
      const std::int64_t n = i1 - i0 + 1;
      // Rows are short: their mask on the stack, a longer one in `mask`.
      const auto words = static_cast<std::size_t>((n + 63) / 64);
      std::uint64_t short_mask[4] = {0, 0, 0, 0};
      std::uint64_t* bits_of = short_mask;
      if (words > 4) {
        mask.assign(words, 0);
        bits_of = mask.data();
      }
      box_mask(box, row + i0, i0, n, bits_of);
      for (std::size_t word = 0; word < words; ++word)
        for (std::uint64_t bits = bits_of[word]; bits != 0; bits &= bits - 1) {
        const std::int64_t i = i0 + static_cast<std::int64_t>(word * 64) + std::countr_zero(bits);
        const double cx = centre_coordinate(g, 0, i);
        double limit = static_cast<double>(row[i]) * s.to_model;
        const dvec3 p(cx, cy, cz);
        std::array<double, kClusterSize> bound2;
        if constexpr (kSeed) {
          // Strictly above the distance (a centroid is a point of the
          // surface), so the nearest triangle still beats it; the root only
          // when it would lower the value.
          const double u2 = nearest_centroid2(probes, cx, cy, cz) * ((1.0 + 1e-6) * (1.0 + 1e-6));
          if (u2 < limit * limit) row[i] = std::min(row[i], round_up(std::sqrt(u2) * s.to_output));
          continue;
        }
        // The triangles by increasing lower bound, until it reaches the
        // value: usually one exact distance, the nearest.
        lower_bounds(probes, cx, cy, cz, bound2.data());
        for (std::size_t x = probes.count; x < kClusterSize; ++x) bound2[x] = kInfinity;
        for (;;) {
          std::size_t best = 0;
          for (std::size_t x = 1; x < probes.count; ++x)
            if (bound2[x] < bound2[best]) best = x;
          if (!(bound2[best] < limit * limit)) break;
          bound2[best] = kInfinity;
          const double d2 = distance2(probes.triangles[best], p);
          if (d2 >= limit * limit) continue;
          row[i] = std::min(row[i], static_cast<float>(std::sqrt(d2) * s.to_output));
          limit = static_cast<double>(row[i]) * s.to_model;
        }
      }
    }
  }
}

void load(const Mesh& mesh, const ClusterSet& set, const Cluster& c, ProbeBlock& probes) {
  probes.clear();
  for (std::uint32_t y = c.begin; y < c.end; ++y) {
    const std::size_t t = set.order[y];
    probes.add(Triangle(corner(mesh, t, 0), corner(mesh, t, 1), corner(mesh, t, 2)));
  }
}

SlabBins bin_by_slab(const ClusterSet& set, const Grid& g, double band, int threads) {
  SlabBins bins;
  const std::int64_t nz = g.dims.z;
  bins.slabs_per_chunk = std::clamp<std::int64_t>(nz / (8 * threads), 1, 16);
  bins.chunk_count = (nz + bins.slabs_per_chunk - 1) / bins.slabs_per_chunk;
  const std::size_t n = set.clusters.size();
  const double band_voxels = band / g.voxel_size;
  std::vector<std::int64_t> first(n), last(n);
  for (std::size_t x = 0; x < n; ++x) {
    // The same slabs as scatter_cluster's (and so scatter_triangle's for
    // the cluster's triangles), by the same arithmetic.
    const Cluster& c = set.clusters[x];
    const std::int64_t k0 = IndexSpace::first(c.lo.z - band_voxels, nz);
    const std::int64_t k1 = IndexSpace::last(c.hi.z + band_voxels, nz);
    first[x] = k0 / bins.slabs_per_chunk;
    last[x] = k0 <= k1 ? k1 / bins.slabs_per_chunk : first[x] - 1;
  }
  bins.offsets.assign(static_cast<std::size_t>(bins.chunk_count) + 1, 0);
  for (std::size_t x = 0; x < n; ++x)
    for (std::int64_t c = first[x]; c <= last[x]; ++c) ++bins.offsets[static_cast<std::size_t>(c) + 1];
  for (std::size_t c = 1; c < bins.offsets.size(); ++c) bins.offsets[c] += bins.offsets[c - 1];
  bins.clusters.resize(bins.offsets.back());
  std::vector<std::uint64_t> cursor(bins.offsets.begin(), bins.offsets.end() - 1);
  for (std::size_t x = 0; x < n; ++x)
    for (std::int64_t c = first[x]; c <= last[x]; ++c)
      bins.clusters[cursor[static_cast<std::size_t>(c)]++] = static_cast<std::uint32_t>(x);
  return bins;
}

}  // namespace

BandPlan plan_band(const Mesh& mesh, const Grid& g, const BandSetup& s, int threads) {
  BandPlan plan;
  plan.set = make_clusters(mesh, g, threads);
  plan.bins = bin_by_slab(plan.set, g, s.band, threads);
  return plan;
}

void scatter_band_chunk(const Mesh& mesh, const Grid& g, const BandSetup& s, const BandPlan& plan, std::int64_t chunk,
                        DenseVolume<float>& values, std::int64_t z_origin, BandScratch& scratch,
                        const std::function<void(std::uint64_t)>& tick) {
  const ClusterSet& set = plan.set;
  const SlabBins& bins = plan.bins;
  // Cancellation and progress every this many triangles (~1 ms of work).
  constexpr std::uint64_t kTick = 512;
  ProbeBlock& probes = *scratch.probes;
  std::vector<std::uint64_t>& mask = scratch.mask;
  const std::int64_t z0 = chunk * bins.slabs_per_chunk, z1 = std::min(g.dims.z, z0 + bins.slabs_per_chunk);
  std::uint64_t pending = 0;
  for (std::uint64_t x = bins.offsets[static_cast<std::size_t>(chunk)];
       x < bins.offsets[static_cast<std::size_t>(chunk) + 1]; ++x) {
    const Cluster& c = set.clusters[bins.clusters[x]];
    if (!c.flat) continue;
    probes.clear();
    for (std::uint32_t y = c.begin; y < c.end; ++y) {
      const std::size_t t = set.order[y];
      probes.add_centroid((corner(mesh, t, 0) + corner(mesh, t, 1) + corner(mesh, t, 2)) / 3.0);
    }
    scatter_cluster<true>(c, probes, g, s, z0, z1, values, z_origin, mask);
  }
  for (std::uint64_t x = bins.offsets[static_cast<std::size_t>(chunk)];
       x < bins.offsets[static_cast<std::size_t>(chunk) + 1]; ++x) {
    const Cluster& c = set.clusters[bins.clusters[x]];
    if (c.flat) {
      load(mesh, set, c, probes);
      scatter_cluster<false>(c, probes, g, s, z0, z1, values, z_origin, mask);
    } else {
      for (std::uint32_t y = c.begin; y < c.end; ++y) {
        const std::size_t t = set.order[y];
        scatter_triangle(Triangle(corner(mesh, t, 0), corner(mesh, t, 1), corner(mesh, t, 2)), g, s, z0, z1, values,
                         z_origin);
      }
    }
    pending += c.end - c.begin;
    if (pending >= kTick) {
      tick(pending);
      pending = 0;
    }
  }
  tick(pending);
}

std::uint64_t band_triangles(const BandPlan& plan) {
  std::uint64_t total = 0;
  for (const std::uint32_t c : plan.bins.clusters) total += plan.set.clusters[c].end - plan.set.clusters[c].begin;
  return total;
}

BandScratch::BandScratch() : probes(std::make_unique<ProbeBlock>()) {}
BandScratch::~BandScratch() = default;
BandScratch::BandScratch(BandScratch&&) noexcept = default;
BandScratch& BandScratch::operator=(BandScratch&&) noexcept = default;

void scatter_band(const Mesh& mesh, const Grid& g, const BandSetup& s, const BandPlan& plan, int threads,
                  DenseVolume<float>& values, const detail::ProgressSpan& progress) {
  const std::uint64_t total = std::max<std::uint64_t>(band_triangles(plan), 1);
  std::atomic<std::uint64_t> done{0};
  parallel_for(0, plan.bins.chunk_count, 1, threads, [&](std::int64_t c0, std::int64_t c1) {
    BandScratch scratch;
    for (std::int64_t chunk = c0; chunk < c1; ++chunk) {
      progress.check_cancelled();
      scatter_band_chunk(mesh, g, s, plan, chunk, values, 0, scratch, [&](std::uint64_t n) {
        progress.check_cancelled();
        progress.report(static_cast<double>(done.fetch_add(n) + n) / static_cast<double>(total));
      });
    }
  });
  progress.report(1.0);
}

}  // namespace voxd::sdf
