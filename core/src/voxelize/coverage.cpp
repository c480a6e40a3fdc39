// Coverage voxelization: crossings of k x k rays per column, then one sweep
// per column over the rays' inside runs. See voxd/voxelize/coverage.h.
#include "voxd/voxelize/coverage.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <vector>

#include "voxd/bit_slabs.h"
#include "voxd/detail/coverage_gpu.h"
#include "voxd/error.h"
#include "voxd/parallel.h"
#include "voxelize/coverage_device.h"
#include "voxelize/coverage_runs.h"
#include "voxelize/fixed_point.h"
#include "voxelize/fixed_point_mesh.h"
#include "voxelize/row_rays.h"
#include "voxelize/splitmix.h"

namespace voxd {
namespace {

using detail::RayCrossing;

class CoverageVoxelizer {
 public:
  CoverageVoxelizer(const Mesh& mesh, const Grid& grid, const CoverageOptions& options)
      : fixed_(mesh, grid), grid_(grid), options_(options), k_(options.rays), rays_(detail::coverage_ray_pattern(options)) {}

  const detail::FixedMesh& fixed() const { return fixed_; }

  // Rows [k0, k1) of the grid into `out`, whose first layer is k0.
  void fill(const detail::RayRows& rows, std::int64_t k0, std::int64_t k1, DenseVolume<float>& out,
            JobControl* control) const {
    using Events = detail::RunEvents;
    rows.run<Events>(
        k0, k1, control,
        [&](std::int64_t k, Events&) {
          return [this, k](std::int64_t j, int r, std::int64_t& pu, std::int64_t& pv) {
            detail::coverage_ray_position(rays_, j, k, r / k_, r % k_, pu, pv);
          };
        },
        [&](std::int64_t k, const std::vector<RayCrossing>& crossings, Events& events) {
          for (std::size_t c = 0; c < crossings.size();) {
            std::size_t e = c;
            while (e < crossings.size() && crossings[e].column == crossings[c].column) ++e;
            float* row = out.slab(k - k0) + static_cast<std::int64_t>(crossings[c].column) * grid_.dims.x;
            fill_column(crossings.data() + c, crossings.data() + e, row, events);
            c = e;
          }
        });
  }

 private:
  // One column: its rays' inside runs, integrated (exact) or sampled
  // (uniform) into the column's voxels.
  void fill_column(const RayCrossing* begin, const RayCrossing* end, float* row, detail::RunEvents& events) const {
    detail::collect_run_events(begin, end, static_cast<double>(grid_.dims.x), 1.0f / static_cast<float>(k_ * k_), events);
    if (events.empty()) return;
    if (options_.sampling == CoverageSampling::uniform)
      detail::sample_runs(events, row, grid_.dims.x, options_.points);
    else
      detail::integrate_runs(events, row, grid_.dims.x);
    detail::clamp_coverage(row, grid_.dims.x);
  }

  detail::FixedMesh fixed_;
  Grid grid_;
  CoverageOptions options_;
  int k_;
  detail::CoverageRayPattern rays_;
};

int thread_count(const CoverageOptions& options) { return options.threads > 0 ? options.threads : default_thread_count(); }

// Where options.device sends the work: the GPU when it resolves to cuda (an
// error there if device is cuda; automatic leaves what the GPU fails to the
// CPU, whose floats are the same, unless `handed_on` says that slabs have
// already gone to the caller), else nothing and the CPU's code runs.
template <typename OnGpu>
bool ran_on_gpu(const CoverageOptions& options, const Grid& grid, CoverageRunReport* report, const OnGpu& on_gpu,
                const bool& handed_on = false) {
  if (coverage_device_for(options, grid) == ComputeDevice::cuda) {
    if (options.device == ComputeDevice::cuda) {
      on_gpu();
      return true;
    }
    try {
      on_gpu();
      return true;
    } catch (const Error& e) {
      if (e.code() == ErrorCode::cancelled || handed_on) throw;
    } catch (const std::runtime_error&) {
      if (handed_on) throw;
    }
  }
  if (report) *report = CoverageRunReport{};
  return false;
}

}  // namespace

namespace detail {
CoverageRayPattern coverage_ray_pattern(const CoverageOptions& options) {
  CoverageRayPattern p;
  p.k = options.rays;
  p.stochastic = options.sampling == CoverageSampling::stochastic;
  p.seed = options.seed;
  // Regular offsets of the rays inside a column, in fixed point relative
  // to the column centre: (a + 1/2) / k - 1/2 voxel.
  for (int a = 0; a < p.k; ++a)
    p.regular[a] = static_cast<std::int64_t>(std::llround(((a + 0.5) / p.k - 0.5) * static_cast<double>(kFixedOne)));
  return p;
}
}  // namespace detail

void validate(const CoverageOptions& options) {
  if (options.rays < 1 || options.rays > 64)
    throw Error(ErrorCode::invalid_argument, "coverage rays must be 1 to 64 per column side, got " + std::to_string(options.rays));
  if (options.points < 1 || options.points > 256)
    throw Error(ErrorCode::invalid_argument, "coverage points must be 1 to 256 per voxel, got " + std::to_string(options.points));
}

ComputeDevice coverage_device_for(const CoverageOptions& options, const Grid& grid) {
  if (options.device != ComputeDevice::automatic) return options.device;
  return grid.voxel_count() >= (std::uint64_t{1} << 21) && cuda_unavailable_reason().empty() ? ComputeDevice::cuda
                                                                                             : ComputeDevice::cpu;
}

DenseVolume<float> voxelize_coverage(const Mesh& mesh, const Grid& grid, const CoverageOptions& options,
                                     JobControl* control, CoverageRunReport* report) {
  validate(options);
  std::optional<DenseVolume<float>> gpu;
  if (ran_on_gpu(options, grid, report, [&] {
        gpu.emplace(detail::voxelize_coverage_on(detail::CoverageBackend::cuda, mesh, grid, options, control, report));
      }))
    return std::move(*gpu);
  DenseVolume<float> out(grid, 0.0f);
  if (grid.voxel_count() == 0) return out;
  const CoverageVoxelizer v(mesh, grid, options);
  const detail::RayRows rows(v.fixed(), grid, options.rays * options.rays, thread_count(options), 0, true);
  v.fill(rows, 0, grid.dims.z, out, control);
  return out;
}

void voxelize_coverage_streamed(const Mesh& mesh, const Grid& grid, const CoverageOptions& options,
                                std::int64_t slab_layers, const CoverageSlabConsumer& consume, JobControl* control,
                                CoverageRunReport* report) {
  validate(options);
  // A GPU that fails before its first slab leaves the work to the CPU; one
  // that fails later fails the work, since its slabs are gone.
  bool handed_on = false;
  if (ran_on_gpu(
          options, grid, report,
          [&] {
            detail::voxelize_coverage_streamed_on(detail::CoverageBackend::cuda, mesh, grid, options, slab_layers,
                                                  [&](std::int64_t k0, const DenseVolume<float>& slab) {
                                                    handed_on = true;
                                                    consume(k0, slab);
                                                  },
                                                  control, report);
          },
          handed_on))
    return;
  if (grid.voxel_count() == 0) return;
  const std::int64_t nz = grid.dims.z;
  const int threads = thread_count(options);
  // Chunks of a few rows, so each slab has work for every thread; a slab is
  // a whole number of chunks (as in voxelize_streamed).
  const std::int64_t layers_wanted = std::clamp<std::int64_t>(slab_layers, 1, nz);
  const std::int64_t per_chunk = std::max<std::int64_t>(1, layers_wanted / (4 * threads));
  const std::int64_t layers = std::min(nz, (layers_wanted + per_chunk - 1) / per_chunk * per_chunk);
  const CoverageVoxelizer v(mesh, grid, options);
  const detail::RayRows rows(v.fixed(), grid, options.rays * options.rays, threads, per_chunk, true);
  // One slab's memory, cleared and reused: fresh pages cost the kernel's
  // zeroing and a fault each (docs/benchmarks.md); the last, shorter slab
  // is one of its own size.
  std::optional<DenseVolume<float>> slab;
  for (std::int64_t k0 = 0; k0 < nz; k0 += layers) {
    if (control) control->check_cancelled();
    const std::int64_t n = std::min(layers, nz - k0);
    if (!slab || slab->grid().dims.z != n) {
      slab.emplace(slab_grid(grid, k0, n), 0.0f);
    } else {
      slab->move_to(slab_grid(grid, k0, n));
      parallel_for(0, static_cast<std::int64_t>(slab->values().size()), std::int64_t{1} << 22, threads,
                   [&](std::int64_t a, std::int64_t b) { std::fill(slab->values().begin() + a, slab->values().begin() + b, 0.0f); });
    }
    v.fill(rows, k0, k0 + n, *slab, control);
    consume(k0, *slab);
  }
}

DenseVolume<std::uint8_t> coverage_bytes(const DenseVolume<float>& coverage, int threads) {
  DenseVolume<std::uint8_t> out(coverage.grid(), 0);
  // Blocks of values, not layers: a streamed slab may be a single layer.
  parallel_for(0, static_cast<std::int64_t>(coverage.values().size()), std::int64_t{1} << 20, threads,
               [&](std::int64_t a, std::int64_t b) {
    const float* in = coverage.values().data();
    std::uint8_t* dst = out.values().data();
    for (auto i = static_cast<std::size_t>(a); i < static_cast<std::size_t>(b); ++i) {
      // lround of the float product, without the library call: y is in
      // [0, 255] and y + 0.5 is exact in double, so the floor is lround(y).
      const float y = std::clamp(in[i], 0.0f, 1.0f) * 255.0f;
      dst[i] = static_cast<std::uint8_t>(static_cast<double>(y) + 0.5);
    }
  });
  return out;
}

void CoveredVoxels::add(const DenseVolume<float>& slab, int threads) {
  // Each layer in fixed blocks, each block over four interleaved sums (so
  // neither one thread nor one chain of additions bounds a layer of a huge
  // grid); the blocks added in order into the layer's sum, the layers in
  // order into the total: the same bits on any thread count and any slabs.
  constexpr std::size_t kBlock = std::size_t{1} << 16;
  const std::size_t layer = slab.slab_size(), blocks = std::max<std::size_t>((layer + kBlock - 1) / kBlock, 1);
  const auto layers = static_cast<std::size_t>(slab.grid().dims.z);
  std::vector<double> block_sums(layers * blocks, 0.0);
  parallel_for(0, static_cast<std::int64_t>(layers * blocks), 16, threads, [&](std::int64_t a, std::int64_t b) {
    for (auto item = static_cast<std::size_t>(a); item < static_cast<std::size_t>(b); ++item) {
      const std::size_t k = item / blocks, begin = item % blocks * kBlock, end = std::min(begin + kBlock, layer);
      const float* v = slab.slab(static_cast<std::int64_t>(k));
      double s[4] = {0.0, 0.0, 0.0, 0.0};
      std::size_t i = begin;
      for (; i + 4 <= end; i += 4)
        for (int l = 0; l < 4; ++l) s[l] += v[i + static_cast<std::size_t>(l)];
      for (; i < end; ++i) s[0] += v[i];
      block_sums[item] = (s[0] + s[1]) + (s[2] + s[3]);
    }
  });
  for (std::size_t k = 0; k < layers; ++k) {
    double layer_sum = 0.0;
    for (std::size_t b = 0; b < blocks; ++b) layer_sum += block_sums[k * blocks + b];
    total_ += layer_sum;
  }
}

double covered_voxels(const DenseVolume<float>& coverage, int threads) {
  CoveredVoxels sum;
  sum.add(coverage, threads);
  return sum.total();
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
