// Coverage voxelization: crossings of k x k rays per column, then one sweep
// per column over the rays' inside runs. See voxd/voxelize/coverage.h.
#include "voxd/voxelize/coverage.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "voxd/error.h"
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

class CoverageVoxelizer {
 public:
  CoverageVoxelizer(const Mesh& mesh, const Grid& grid, const CoverageOptions& options)
      : fixed_(mesh, grid), grid_(grid), options_(options), k_(options.rays) {
    // Regular offsets of the rays inside a column, in fixed point relative
    // to the column centre: (a + 1/2) / k - 1/2 voxel.
    for (int a = 0; a < k_; ++a) {
      regular_.push_back(static_cast<std::int64_t>(
          std::llround(((a + 0.5) / k_ - 0.5) * static_cast<double>(kFixedOne))));
    }
  }

  DenseVolume<float> run(JobControl* control) {
    DenseVolume<float> out(grid_, 0.0f);
    if (grid_.voxel_count() == 0) return out;
    const int threads = options_.threads > 0 ? options_.threads : default_thread_count();
    using Events = std::vector<std::pair<double, float>>;
    detail::for_each_ray_row<Events>(
        fixed_, grid_, k_ * k_, threads, control,
        [&](std::int64_t k, Events&) {
          return [this, k](std::int64_t j, int r, std::int64_t& pu, std::int64_t& pv) {
            ray_position(j, k, r / k_, r % k_, pu, pv);
          };
        },
        [&](std::int64_t k, const std::vector<RayCrossing>& crossings, Events& events) {
          for (std::size_t c = 0; c < crossings.size();) {
            std::size_t e = c;
            while (e < crossings.size() && crossings[e].column == crossings[c].column) ++e;
            float* row = out.slab(k) + static_cast<std::int64_t>(crossings[c].column) * grid_.dims.x;
            fill_column(crossings.data() + c, crossings.data() + e, row, events);
            c = e;
          }
        });
    return out;
  }

 private:
  // The ray's position in fixed point (u = y, v = z) for column j, row k.
  void ray_position(std::int64_t j, std::int64_t k, int a, int b, std::int64_t& pu, std::int64_t& pv) const {
    if (options_.sampling != CoverageSampling::stochastic) {
      pu = j * kFixedOne + regular_[static_cast<std::size_t>(a)];
      pv = k * kFixedOne + regular_[static_cast<std::size_t>(b)];
      return;
    }
    const std::uint64_t ray = static_cast<std::uint64_t>(k) << 20 ^ static_cast<std::uint64_t>(a * k_ + b);
    const std::uint64_t h = splitmix_hash(
        options_.seed ^ splitmix_hash(static_cast<std::uint64_t>(j) * 0x100000001b3ull ^ splitmix_hash(ray)));
    const double one = static_cast<double>(kFixedOne);
    pu = j * kFixedOne + static_cast<std::int64_t>(std::floor(((a + unit_interval(h)) / k_ - 0.5) * one));
    pv = k * kFixedOne + static_cast<std::int64_t>(std::floor(((b + unit_interval(splitmix_hash(h))) / k_ - 0.5) * one));
  }

  // One column: pair each ray's sorted crossings into inside runs, then
  // integrate (exact) or sample (uniform) them into the column's voxels.
  void fill_column(const RayCrossing* begin, const RayCrossing* end, float* row,
                   std::vector<std::pair<double, float>>& events) const {
    const double nx = static_cast<double>(grid_.dims.x);
    const float w = 1.0f / static_cast<float>(k_ * k_);
    events.clear();
    for (const RayCrossing* r = begin; r != end;) {
      const RayCrossing* e = r;
      while (e != end && e->ray == r->ray) ++e;
      // An odd count (open mesh) leaves the last crossing unpaired.
      for (const RayCrossing* c = r; c + 1 < e; c += 2) {
        const double x0 = std::clamp(c->x, 0.0, nx), x1 = std::clamp((c + 1)->x, 0.0, nx);
        if (x1 > x0) {
          events.emplace_back(x0, w);
          events.emplace_back(x1, -w);
        }
      }
      r = e;
    }
    if (events.empty()) return;
    std::sort(events.begin(), events.end());
    if (options_.sampling == CoverageSampling::uniform) {
      sample_runs(events, row);
    } else {
      integrate_runs(events, row);
    }
    // Rounding of the float sums can step a hair outside [0, 1].
    for (std::int64_t i = 0; i < grid_.dims.x; ++i) row[i] = std::clamp(row[i], 0.0f, 1.0f);
  }

  // Exact: the inside share f is constant between events; each voxel gets
  // the integral of f over its extent.
  void integrate_runs(const std::vector<std::pair<double, float>>& events, float* row) const {
    double f = 0.0, prev = 0.0;
    for (const auto& [x, delta] : events) {
      if (f > 0.0 && x > prev) {
        const auto i0 = static_cast<std::int64_t>(std::floor(prev));
        const auto i1 = std::min(static_cast<std::int64_t>(std::floor(x)), grid_.dims.x - 1);
        if (i0 == i1) {
          row[i0] += static_cast<float>(f * (x - prev));
        } else {
          row[i0] += static_cast<float>(f * (static_cast<double>(i0 + 1) - prev));
          for (std::int64_t i = i0 + 1; i < i1; ++i) row[i] += static_cast<float>(f);
          row[i1] += static_cast<float>(f * (x - static_cast<double>(i1)));
        }
      }
      f += delta;
      prev = x;
    }
  }

  // The paper's point sampling: m points per voxel at (i + (p + 1/2) / m),
  // each counted with the number of rays inside there.
  void sample_runs(const std::vector<std::pair<double, float>>& events, float* row) const {
    const int m = options_.points;
    double f = 0.0, prev = 0.0;
    for (const auto& [x, delta] : events) {
      if (f > 0.0 && x > prev) {
        // Points s = i * m + p with prev <= (s + 1/2) / m < x.
        const auto s0 = static_cast<std::int64_t>(std::ceil(prev * m - 0.5));
        const auto s1 = static_cast<std::int64_t>(std::ceil(x * m - 0.5));  // exclusive
        for (std::int64_t s = std::max<std::int64_t>(s0, 0); s < s1 && s < grid_.dims.x * m; ++s)
          row[s / m] += static_cast<float>(f / m);
      }
      f += delta;
      prev = x;
    }
  }

  detail::FixedMesh fixed_;
  Grid grid_;
  CoverageOptions options_;
  int k_;
  std::vector<std::int64_t> regular_;
};

}  // namespace

DenseVolume<float> voxelize_coverage(const Mesh& mesh, const Grid& grid, const CoverageOptions& options,
                                     JobControl* control) {
  if (options.rays < 1 || options.rays > 64)
    throw Error(ErrorCode::invalid_argument, "coverage rays must be 1 to 64 per column side, got " + std::to_string(options.rays));
  if (options.points < 1 || options.points > 256)
    throw Error(ErrorCode::invalid_argument, "coverage points must be 1 to 256 per voxel, got " + std::to_string(options.points));
  CoverageVoxelizer v(mesh, grid, options);
  return v.run(control);
}

DenseVolume<std::uint8_t> coverage_bytes(const DenseVolume<float>& coverage, int threads) {
  DenseVolume<std::uint8_t> out(coverage.grid(), 0);
  const std::size_t slab = coverage.slab_size();
  parallel_for(0, coverage.grid().dims.z, 1, threads, [&](std::int64_t k0, std::int64_t k1) {
    const float* in = coverage.slab(k0);
    std::uint8_t* dst = out.slab(k0);
    for (std::size_t i = 0, n = slab * static_cast<std::size_t>(k1 - k0); i < n; ++i) {
      // lround of the float product, without the library call: y is in
      // [0, 255] and y + 0.5 is exact in double, so the floor is lround(y).
      const float y = std::clamp(in[i], 0.0f, 1.0f) * 255.0f;
      dst[i] = static_cast<std::uint8_t>(static_cast<double>(y) + 0.5);
    }
  });
  return out;
}

double covered_voxels(const DenseVolume<float>& coverage, int threads) {
  // A sum per slab, added in slab order: the same total on any thread count.
  std::vector<double> slab_sums(static_cast<std::size_t>(coverage.grid().dims.z), 0.0);
  const std::size_t slab = coverage.slab_size();
  parallel_for(0, coverage.grid().dims.z, 1, threads, [&](std::int64_t k0, std::int64_t k1) {
    for (std::int64_t k = k0; k < k1; ++k) {
      const float* v = coverage.slab(k);
      double sum = 0.0;
      for (std::size_t i = 0; i < slab; ++i) sum += v[i];
      slab_sums[static_cast<std::size_t>(k)] = sum;
    }
  });
  double total = 0.0;
  for (double s : slab_sums) total += s;
  return total;
}

BitVolume coverage_threshold(const DenseVolume<float>& coverage, float threshold) {
  if (!(threshold > 0.0f && threshold <= 1.0f))
    throw Error(ErrorCode::invalid_argument, "coverage threshold must be in (0, 1]");
  const Grid& g = coverage.grid();
  BitVolume out(g);
  for (std::int64_t k = 0; k < g.dims.z; ++k)
    for (std::int64_t j = 0; j < g.dims.y; ++j) {
      const float* row = coverage.slab(k) + j * g.dims.x;
      std::uint64_t* bits = out.row(j, k);
      for (std::int64_t i = 0; i < g.dims.x; ++i)
        if (row[i] >= threshold) bits[i >> 6] |= std::uint64_t{1} << (i & 63);
    }
  return out;
}

}  // namespace voxd
