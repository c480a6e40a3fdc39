// Local thickness: distance transform -> distance ridge -> paint the ridge
// balls, largest first, each voxel written once. See voxd/local_thickness.h.
#include "voxd/local_thickness.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>

#include "analysis/distance_transform_impl.h"
#include "voxd/error.h"
#include "voxd/parallel.h"

namespace voxd {
namespace {

// floor(sqrt(n)), exact for every n < 2^62 (the double estimate is corrected).
std::int64_t isqrt(std::int64_t n) {
  auto r = static_cast<std::int64_t>(std::sqrt(static_cast<double>(n)));
  while (r * r > n) --r;
  while ((r + 1) * (r + 1) <= n) ++r;
  return r;
}

std::int64_t ceil_sqrt(std::int64_t n) {
  const std::int64_t r = isqrt(n);
  return r * r == n ? r : r + 1;
}

struct RidgePoint {
  std::int32_t x, y, z;
  std::uint32_t d2;
};

// The ball at c (squared radius R) lies inside the ball at c + e (squared
// radius R') whenever sqrt(R') >= sqrt(R) + |e|, i.e.
// R' >= R + |e|^2 + 2 sqrt(R |e|^2). This is the continuous containment, a
// sufficient condition for the lattice balls, so dropping such a c never
// changes the maximum: the containing ball is larger and carries a larger
// value, and it is itself kept or contained in a larger one (the radius grows
// strictly along the chain, so the chain ends at a ridge voxel).
struct Containment {
  std::uint64_t need[4];  // indexed by |e|^2 = 1, 2, 3
  explicit Containment(std::int64_t r2) {
    need[0] = 0;
    for (std::int64_t e2 = 1; e2 <= 3; ++e2) {
      need[e2] = static_cast<std::uint64_t>(r2 + e2 + ceil_sqrt(4 * r2 * e2));
    }
  }
};

// Ridge voxels of slabs [k0, k1), in x-fastest order.
void collect_ridge(const DenseVolume<std::uint32_t>& edt, std::int64_t k0, std::int64_t k1,
                   std::vector<RidgePoint>& out) {
  const auto d = edt.grid().dims;
  auto value = [&](std::int64_t i, std::int64_t j, std::int64_t k) -> std::uint64_t {
    if (i < 0 || j < 0 || k < 0 || i >= d.x || j >= d.y || k >= d.z) return 0;
    return edt.at(i, j, k);
  };
  for (std::int64_t k = k0; k < k1; ++k)
    for (std::int64_t j = 0; j < d.y; ++j) {
      const std::uint32_t* row = edt.slab(k) + j * d.x;
      for (std::int64_t i = 0; i < d.x; ++i) {
        const std::uint32_t r2 = row[i];
        if (r2 == 0) continue;
        const Containment c(r2);
        bool contained = false;
        for (int dz = -1; dz <= 1 && !contained; ++dz)
          for (int dy = -1; dy <= 1 && !contained; ++dy)
            for (int dx = -1; dx <= 1 && !contained; ++dx) {
              const int e2 = dx * dx + dy * dy + dz * dz;
              if (e2 == 0) continue;
              contained = value(i + dx, j + dy, k + dz) >= c.need[e2];
            }
        if (!contained) {
          out.push_back({static_cast<std::int32_t>(i), static_cast<std::int32_t>(j), static_cast<std::int32_t>(k), r2});
        }
      }
    }
}

// Per-row skip list over the voxels still to paint: next[x] == x for a filled
// voxel without a value yet; otherwise it points further right (possibly to
// nx, one past the row). Path halving keeps the walks short.
inline std::uint32_t find_unpainted(std::uint32_t* next, std::uint32_t x, std::uint32_t nx) {
  while (x < nx && next[x] != x) {
    const std::uint32_t n = next[x];
    if (n < nx) next[x] = next[n];
    x = n;
  }
  return x;
}

}  // namespace

DenseVolume<float> local_thickness(const BitVolume& solid, int threads, JobControl* control) {
  const Grid& grid = solid.grid();
  const std::int64_t nx = grid.dims.x, ny = grid.dims.y, nz = grid.dims.z;
  const int nthreads = threads > 0 ? threads : default_thread_count();
  const detail::ProgressSpan progress{control, 0.0, 1.0};

  DenseVolume<std::uint32_t> edt = detail::squared_distance_transform(solid, nthreads, progress.part(0.0, 0.4));
  DenseVolume<float> out(grid, 0.0f);
  if (grid.voxel_count() == 0) return out;

  // Distance ridge, per z-chunk, concatenated in chunk order.
  const std::int64_t grain = std::max<std::int64_t>(1, nz / (nthreads * 8));
  const std::int64_t chunks = (nz + grain - 1) / grain;
  std::vector<std::vector<RidgePoint>> parts(static_cast<std::size_t>(chunks));
  parallel_for(0, nz, grain, nthreads, [&](std::int64_t k0, std::int64_t k1) {
    progress.check_cancelled();
    collect_ridge(edt, k0, k1, parts[static_cast<std::size_t>(k0 / grain)]);
  });
  std::vector<RidgePoint> ridge;
  {
    std::size_t total = 0;
    for (const auto& p : parts) total += p.size();
    ridge.reserve(total);
    for (auto& p : parts) {
      ridge.insert(ridge.end(), p.begin(), p.end());
      std::vector<RidgePoint>().swap(p);
    }
  }
  // Largest first; ties in scan order so the work order is reproducible (the
  // result does not depend on it: equal radii paint equal values).
  std::stable_sort(ridge.begin(), ridge.end(), [](const RidgePoint& a, const RidgePoint& b) { return a.d2 > b.d2; });
  progress.report(0.5);

  // Paint. Each chunk of slabs first turns its part of the distance map into
  // skip lists (the distances are no longer needed), then paints the discs of
  // every ridge ball crossing it, largest ball first, so the first value a
  // voxel gets is its maximum and the skip list never visits it again.
  std::atomic<std::int64_t> slabs_done{0};
  std::vector<float> values(ridge.size());
  for (std::size_t r = 0; r < ridge.size(); ++r) {
    values[r] = static_cast<float>(2.0 * std::sqrt(static_cast<double>(ridge[r].d2)));
  }
  parallel_for(0, nz, grain, nthreads, [&](std::int64_t k0, std::int64_t k1) {
    progress.check_cancelled();
    const auto unx = static_cast<std::uint32_t>(nx);
    for (std::int64_t k = k0; k < k1; ++k) {
      std::uint32_t* s = edt.slab(k);
      for (std::int64_t j = 0; j < ny; ++j) {
        std::uint32_t* next = s + j * nx;
        for (std::uint32_t i = 0; i < unx; ++i) next[i] = next[i] != 0 ? i : i + 1;
      }
    }
    for (std::size_t r = 0; r < ridge.size(); ++r) {
      const RidgePoint& p = ridge[r];
      const std::int64_t R = p.d2;
      const std::int64_t rz = isqrt(R);
      const std::int64_t zlo = std::max<std::int64_t>(k0, p.z - rz);
      const std::int64_t zhi = std::min<std::int64_t>(k1 - 1, p.z + rz);
      if (zlo > zhi) continue;
      if ((r & 1023) == 0) progress.check_cancelled();
      const float value = values[r];
      for (std::int64_t z = zlo; z <= zhi; ++z) {
        const std::int64_t Rz = R - (z - p.z) * (z - p.z);
        const std::int64_t ry = isqrt(Rz);
        const std::int64_t ylo = std::max<std::int64_t>(0, p.y - ry);
        const std::int64_t yhi = std::min<std::int64_t>(ny - 1, p.y + ry);
        std::uint32_t* next_slab = edt.slab(z);
        float* out_slab = out.slab(z);
        for (std::int64_t y = ylo; y <= yhi; ++y) {
          const std::int64_t rx = isqrt(Rz - (y - p.y) * (y - p.y));
          const auto xlo = static_cast<std::uint32_t>(std::max<std::int64_t>(0, p.x - rx));
          const auto xend = static_cast<std::uint32_t>(std::min<std::int64_t>(nx, p.x + rx + 1));
          std::uint32_t* next = next_slab + y * nx;
          float* row = out_slab + y * nx;
          std::uint32_t x = find_unpainted(next, xlo, unx);
          while (x < xend) {
            row[x] = value;
            next[x] = x + 1;
            x = find_unpainted(next, x + 1, unx);
          }
        }
      }
    }
    const std::int64_t d = slabs_done.fetch_add(k1 - k0) + (k1 - k0);
    progress.report(0.5 + 0.5 * static_cast<double>(d) / static_cast<double>(nz));
  });
  progress.report(1.0);
  return out;
}

ThicknessStatistics thickness_statistics(const DenseVolume<float>& thickness, int bins) {
  if (bins < 1) throw Error(ErrorCode::invalid_argument, "thickness histogram needs at least 1 bin");
  ThicknessStatistics st;
  double sum = 0.0;
  for (float v : thickness.values()) {
    if (v <= 0.0f) continue;
    if (st.voxel_count == 0) st.min = st.max = v;
    st.min = std::min<double>(st.min, v);
    st.max = std::max<double>(st.max, v);
    sum += v;
    ++st.voxel_count;
  }
  if (st.voxel_count == 0) return st;
  st.mean = sum / static_cast<double>(st.voxel_count);
  // Second pass for the variance: sum of squared deviations does not lose
  // precision the way sum(v^2) - n mean^2 does.
  st.histogram.assign(static_cast<std::size_t>(bins), 0);
  const double range = st.max - st.min;
  double ss = 0.0;
  for (float v : thickness.values()) {
    if (v <= 0.0f) continue;
    ss += (v - st.mean) * (v - st.mean);
    std::int64_t b = range > 0.0 ? static_cast<std::int64_t>((v - st.min) / range * bins) : 0;
    b = std::clamp<std::int64_t>(b, 0, bins - 1);
    ++st.histogram[static_cast<std::size_t>(b)];
  }
  st.std_dev = std::sqrt(ss / static_cast<double>(st.voxel_count));
  return st;
}

ThicknessErrorBound thickness_error_bound() { return {}; }

std::string thickness_error_statement(double voxel_size) {
  const ThicknessErrorBound b = thickness_error_bound();
  char text[400];
  std::snprintf(text, sizeof text,
                "-%g to +%g voxels (-%g to +%g model units) against the mesh's wall thickness: the voxelization "
                "places each face anywhere within a voxel, and a wall N voxels thick reports N (even N) or N + 1 "
                "(odd N)",
                b.below_voxels, b.above_voxels, b.below_voxels * voxel_size, b.above_voxels * voxel_size);
  return text;
}

}  // namespace voxd
