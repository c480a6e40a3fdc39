// Signed distance field: the narrow band by scattering triangles to voxels
// (Jones 1996), exact nearest-triangle queries for the rest of the grid when
// asked, the sign from the solid voxelization. See voxd/voxelize/sdf.h.
#include "voxd/detail/sdf_gpu.h"
#include "voxd/detail/sdf_tuning.h"
#include "voxd/voxelize/sdf.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <exception>
#include <limits>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <glm/geometric.hpp>

#include "analysis/progress_span.h"
#include "voxd/error.h"
#include "voxd/parallel.h"
#include "encode/ordered_pipeline.h"
#include "voxd/voxelize/runs.h"
#include "voxelize/sdf_band.h"
#include "voxelize/sdf_fill.h"
#include "voxelize/sdf_tree.h"
#include "voxelize/sdf_triangle.h"

namespace voxd {
namespace {

using glm::dvec3;
using sdf::BandSetup;
using sdf::centre_coordinate;
using sdf::kInfinity;
using sdf::Triangle;
using sdf::TriangleTree;

// ---------------------------------------------------------------------------

// The solid voxelization for the sign, on a JobControl of its own: the
// voxelizers report 0..1 on the control they get, and a JobControl's span
// belongs to whoever runs the job, so it cannot be narrowed here. A watcher
// forwards cancellation in and progress (onto `progress`) out.
BitVolume solid_for_sign(const Mesh& mesh, const Grid& grid, const SdfOptions& options,
                         const detail::ProgressSpan& progress) {
  const VoxelizeOptions vo{VoxelMode::solid, options.inside, options.threads};
  if (!progress.control) return voxelize(mesh, grid, vo, nullptr);
  JobControl inner;
  std::mutex mutex;
  std::condition_variable wake;
  bool finished = false;
  std::thread watcher([&] {
    std::unique_lock lock(mutex);
    while (!wake.wait_for(lock, std::chrono::milliseconds(2), [&] { return finished; })) {
      if (progress.control->cancel_requested()) inner.request_cancel();
      progress.report(inner.progress());
    }
  });
  auto stop = [&] {
    {
      std::lock_guard lock(mutex);
      finished = true;
    }
    wake.notify_one();
    watcher.join();
  };
  BitVolume solid;
  try {
    solid = voxelize(mesh, grid, vo, &inner);
  } catch (...) {
    stop();
    throw;
  }
  stop();
  progress.check_cancelled();
  progress.report(1.0);
  return solid;
}

}  // namespace

namespace sdf {
FillBeyondBand embree_fill_beyond_band = nullptr;
}  // namespace sdf

double point_triangle_distance2(const dvec3& p, const dvec3& a, const dvec3& b, const dvec3& c) {
  return sdf::distance2(Triangle(a, b, c), p);
}

namespace {

// `band_on`: where the band is computed, the CPU's scatter when empty.
DenseVolume<float> compute_sdf(const Mesh& mesh, const Grid& grid, const SdfOptions& options, JobControl* control,
                               const detail::SdfTuning& tuning, BitVolume* solid_out,
                               std::optional<detail::SdfBackend> band_on = std::nullopt,
                               DeviceRunReport* report = nullptr);
DenseVolume<float> finish_sdf(const Mesh& mesh, const Grid& grid, const SdfOptions& options,
                              const detail::SdfTuning& tuning, const BandSetup& s, float clamped, int threads,
                              const detail::ProgressSpan& progress, double band_end, BitVolume solid,
                              DenseVolume<float> values, BitVolume* solid_out);

BandSetup band_setup(const Grid& grid, const SdfOptions& options) {
  if (!(options.band > 0.0) || !std::isfinite(options.band))
    throw Error(ErrorCode::invalid_argument, "the distance band must be a positive number of voxels");
  if (!(grid.voxel_size > 0.0) || !std::isfinite(grid.voxel_size))
    throw Error(ErrorCode::invalid_argument, "the voxel size must be a positive number");
  BandSetup s;
  s.band = options.band * grid.voxel_size;
  s.to_model = options.model_units ? 1.0 : grid.voxel_size;
  s.to_output = options.model_units ? 1.0 : 1.0 / grid.voxel_size;
  return s;
}

// Exactly +-band in the output unit, not band * voxel_size / voxel_size.
float clamped_value(const SdfOptions& options, const BandSetup& s) {
  return static_cast<float>(options.model_units ? s.band : options.band);
}

// Negates the nonzero values of a row's voxels [begin, end) (a value of 0, a
// centre on the surface, stays +0).
inline void negate_nonzero(float* row, std::int64_t begin, std::int64_t end) {
  for (std::int64_t i = begin; i < end; ++i)
    if (row[i] != 0.0f) row[i] = -row[i];
}

}  // namespace

std::optional<std::string> sdf_slabs_refusal(const SdfOptions& options) {
  if (options.device == ComputeDevice::cuda)
    return "device cuda computes the band of the whole grid at once; only the CPU goes slab by slab (device auto or cpu)";
  if (options.full) return "the full field's nearest-triangle queries need the whole grid; only the band goes slab by slab";
  if (options.inside != InsideTest::parity)
    return "the " + std::string(to_string(options.inside)) + " inside test needs the whole grid; only parity signs slab by slab";
  return std::nullopt;
}

void signed_distance_field_slabs(const Mesh& mesh, const Grid& grid, const SdfOptions& options,
                                 const RunSlabConsumer& solid, const ValueSlabConsumer& values, JobControl* control) {
  if (auto refusal = sdf_slabs_refusal(options)) throw Error(ErrorCode::invalid_argument, *refusal);
  const BandSetup s = band_setup(grid, options);
  const float clamped = clamped_value(options, s);
  const int threads = options.threads > 0 ? options.threads : default_thread_count();
  const detail::ProgressSpan progress{control, 0.0, 1.0};
  if (grid.voxel_count() == 0) return;

  // The solid as runs, kept whole for the sign (about N^2 runs where its
  // bits are N^3 / 8 bytes), and handed on.
  RunSlab inside(grid);
  VoxelizeOptions vo{VoxelMode::solid, InsideTest::parity, threads};
  voxelize_runs(mesh, grid, vo, [&](std::int64_t k0, const RunSlab& slab) {
    solid(k0, slab);
    inside.append_rows(slab);
  });
  progress.check_cancelled();
  progress.report(0.1);
  const sdf::BandPlan plan = sdf::plan_band(mesh, grid, s, threads);
  progress.check_cancelled();

  // Chunk by chunk of the band's z-slabs, each in a buffer of its slot
  // (reused: no fresh pages to clear), in order to the consumer.
  const detail::ProgressSpan band = progress.part(0.15, 1.0);
  const std::uint64_t total = std::max<std::uint64_t>(sdf::band_triangles(plan), 1);
  std::atomic<std::uint64_t> done{0};
  const bool negate_inside = options.sign == SignConvention::inside_negative;
  const std::int64_t per_chunk = plan.bins.slabs_per_chunk, nx = grid.dims.x, ny = grid.dims.y;
  // One slot a thread and one being written: each is a slab of fresh pages
  // (16 MB at 512^3) the first time.
  const std::size_t slot_count = static_cast<std::size_t>(std::min<std::int64_t>(plan.bins.chunk_count, threads + 1));
  std::vector<ValueVolume> buffers(slot_count, ValueVolume(DenseVolume<float>()));
  std::vector<sdf::BandScratch> scratch(slot_count);
  encode::run_ordered_pipeline(
      plan.bins.chunk_count, threads, slot_count,
      [&](std::int64_t chunk, std::size_t slot) {
        band.check_cancelled();
        const std::int64_t z0 = chunk * per_chunk, n = std::min(per_chunk, grid.dims.z - z0);
        const Grid slab = slab_grid(grid, z0, n);
        auto& v = std::get<DenseVolume<float>>(buffers[slot]);
        if (v.grid().dims != slab.dims) {
          v = DenseVolume<float>(slab, clamped);
        } else {
          v.move_to(slab);
          std::fill(v.values().begin(), v.values().end(), clamped);
        }
        sdf::scatter_band_chunk(mesh, grid, s, plan, chunk, v, z0, scratch[slot], [&](std::uint64_t d) {
          band.check_cancelled();
          band.report(static_cast<double>(done.fetch_add(d) + d) / static_cast<double>(total));
        });
        // Sign: inside (or outside) runs of each row negated.
        for (std::int64_t k = 0; k < n; ++k)
          for (std::int64_t j = 0; j < ny; ++j) {
            float* row = v.slab(k) + j * nx;
            const auto runs = inside.row(j, z0 + k);
            std::int64_t from = 0;  // outside voxels start here
            for (std::size_t r = 0; r < runs.size(); r += 2) {
              if (negate_inside)
                negate_nonzero(row, runs[r], runs[r + 1]);
              else
                negate_nonzero(row, from, runs[r]);
              from = runs[r + 1];
            }
            if (!negate_inside) negate_nonzero(row, from, nx);
          }
      },
      [&](std::int64_t chunk, std::size_t slot) { values(chunk * per_chunk, buffers[slot]); });
  progress.report(1.0);
}

ComputeDevice sdf_device_for(const SdfOptions& options, const Grid& grid) {
  if (options.device != ComputeDevice::automatic) return options.device;
  return grid.voxel_count() >= (std::uint64_t{1} << 21) && cuda_unavailable_reason().empty() ? ComputeDevice::cuda
                                                                                             : ComputeDevice::cpu;
}

DenseVolume<float> signed_distance_field(const Mesh& mesh, const Grid& grid, const SdfOptions& options,
                                         JobControl* control) {
  return signed_distance_field(mesh, grid, options, control, nullptr, nullptr);
}

DenseVolume<float> signed_distance_field(const Mesh& mesh, const Grid& grid, const SdfOptions& options,
                                         JobControl* control, BitVolume* solid, DeviceRunReport* report) {
  if (sdf_device_for(options, grid) == ComputeDevice::cuda) {
    if (options.device == ComputeDevice::cuda)
      return compute_sdf(mesh, grid, options, control, detail::SdfTuning{}, solid, detail::SdfBackend::cuda, report);
    // automatic: a GPU that cannot take the band (its memory taken by
    // others, a CUDA failure) leaves the field to the CPU, whose bits are
    // the same; the report says where it ran. Cancellation is not a failure.
    try {
      return compute_sdf(mesh, grid, options, control, detail::SdfTuning{}, solid, detail::SdfBackend::cuda, report);
    } catch (const Error& e) {
      if (e.code() == ErrorCode::cancelled) throw;
    } catch (const std::runtime_error&) {
    }
  }
  if (report) *report = DeviceRunReport{};
  return compute_sdf(mesh, grid, options, control, detail::SdfTuning{}, solid);
}

namespace detail {
DenseVolume<float> signed_distance_field_on(SdfBackend backend, const Mesh& mesh, const Grid& grid,
                                            const SdfOptions& options, JobControl* control, BitVolume* solid,
                                            DeviceRunReport* report) {
  return compute_sdf(mesh, grid, options, control, SdfTuning{}, solid, backend, report);
}

std::uint64_t sdf_scene_bytes(const Mesh& mesh, const Grid& grid, const SdfOptions& options) {
  const BandSetup s = band_setup(grid, options);
  return sdf::scene_bytes(mesh, grid, s, clamped_value(options, s));
}
}  // namespace detail

DenseVolume<float> signed_distance_field(const Mesh& mesh, const Grid& grid, const SdfOptions& options,
                                         JobControl* control, const detail::SdfTuning& tuning) {
  return compute_sdf(mesh, grid, options, control, tuning, nullptr);
}

namespace {

DenseVolume<float> compute_sdf(const Mesh& mesh, const Grid& grid, const SdfOptions& options, JobControl* control,
                               const detail::SdfTuning& tuning, BitVolume* solid_out,
                               std::optional<detail::SdfBackend> band_on, DeviceRunReport* report) {
  const BandSetup s = band_setup(grid, options);
  const float clamped = clamped_value(options, s);
  const int threads = options.threads > 0 ? options.threads : default_thread_count();
  const detail::ProgressSpan progress{control, 0.0, 1.0};

  if (grid.voxel_count() == 0) {
    if (report) *report = DeviceRunReport{};
    return DenseVolume<float>(grid, clamped);
  }
  const double band_end = options.full ? 0.25 : 1.0;
  DenseVolume<float> values;
  if (band_on) {
    // A GPU asked for and missing is the user's to fix, before any work.
    if (*band_on == detail::SdfBackend::cuda && !cuda_unavailable_reason().empty())
      throw Error(ErrorCode::invalid_argument, cuda_unavailable_reason());
    BitVolume solid = solid_for_sign(mesh, grid, options, progress.part(0.0, 0.15));
    values = DenseVolume<float>(grid, DenseVolume<float>::Uninitialized{});  // the device writes every voxel
    sdf::band_on_device(*band_on, mesh, grid, s, clamped, threads, options.gpu_memory, values,
                        progress.part(0.15, band_end), report);
    return finish_sdf(mesh, grid, options, tuning, s, clamped, threads, progress, band_end, std::move(solid),
                      std::move(values), solid_out);
  }
  if (report) *report = DeviceRunReport{};
  // The output is filled on a thread of its own meanwhile: one thread
  // writing every value (and, first touch, faulting every page in) is a
  // sizeable part of the band's time at 512^3 (~0.4 GB), and the solid and
  // the clusters keep the other cores busy.
  std::exception_ptr fill_error;
  std::thread filler([&] {
    try {
      values = DenseVolume<float>(grid, clamped);
    } catch (...) {
      fill_error = std::current_exception();
    }
  });
  struct Join {
    std::thread& thread;
    ~Join() {
      if (thread.joinable()) thread.join();
    }
  } join{filler};
  BitVolume solid = solid_for_sign(mesh, grid, options, progress.part(0.0, 0.15));
  const sdf::BandPlan plan = sdf::plan_band(mesh, grid, s, threads);
  filler.join();
  if (fill_error) std::rethrow_exception(fill_error);
  progress.check_cancelled();
  sdf::scatter_band(mesh, grid, s, plan, threads, values, progress.part(0.15, band_end));
  return finish_sdf(mesh, grid, options, tuning, s, clamped, threads, progress, band_end, std::move(solid),
                    std::move(values), solid_out);
}

// After the band: the full field's queries where asked, then the sign.
DenseVolume<float> finish_sdf(const Mesh& mesh, const Grid& grid, const SdfOptions& options,
                              const detail::SdfTuning& tuning, const BandSetup& s, float clamped, int threads,
                              const detail::ProgressSpan& progress, double band_end, BitVolume solid,
                              DenseVolume<float> values, BitVolume* solid_out) {
  if (options.full) {
    const detail::ProgressSpan rest = progress.part(band_end, 1.0);
    if (tuning.nearest == detail::SdfTuning::Nearest::embree) {
      // Linked only into the tests and benchmarks (voxd_sdf_embree): the
      // engine itself needs no Embree.
      if (!sdf::embree_fill_beyond_band)
        throw Error(ErrorCode::invalid_argument, "nearest-triangle queries by Embree are not linked into this program");
      sdf::embree_fill_beyond_band(mesh, grid, s, clamped, threads, values, rest);
    } else {
      const TriangleTree tree(mesh, threads, rest.part(0.0, 0.1));
      fill_beyond_band(tree, grid, s, clamped, threads, values, rest.part(0.1, 1.0));
    }
  }

  // Sign; a value of 0 (a centre on the surface) stays +0.
  const bool negate_inside = options.sign == SignConvention::inside_negative;
  const std::int64_t nx = grid.dims.x, ny = grid.dims.y;
  parallel_for(0, grid.dims.z, 1, threads, [&](std::int64_t k0, std::int64_t k1) {
    for (std::int64_t k = k0; k < k1; ++k)
      for (std::int64_t j = 0; j < ny; ++j) {
        // A word of the solid at a time: whole words outside (or inside) the
        // solid are skipped, then the voxels to negate one bit at a time.
        float* row = values.slab(k) + j * nx;
        const std::uint64_t* bits = solid.row(j, k);
        for (std::int64_t w = 0; w * 64 < nx; ++w) {
          std::uint64_t flip = negate_inside ? bits[w] : ~bits[w];
          if (nx - w * 64 < 64) flip &= (std::uint64_t{1} << (nx - w * 64)) - 1;  // bits past the row
          for (; flip != 0; flip &= flip - 1) {
            float& v = row[w * 64 + std::countr_zero(flip)];
            if (v != 0.0f) v = -v;
          }
        }
      }
  });
  progress.report(1.0);
  if (solid_out) *solid_out = std::move(solid);
  return values;
}

}  // namespace

}  // namespace voxd
