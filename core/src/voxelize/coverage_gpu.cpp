// Grey coverage slab by slab on a device: the CUDA GPU, or the host
// emulation of its kernels. See voxd/detail/coverage_gpu.h.
#include "voxd/detail/coverage_gpu.h"

#include <algorithm>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "voxd/bit_slabs.h"
#include "voxd/compute_device.h"
#include "voxd/error.h"
#include "voxd/parallel.h"
#include "voxelize/coverage_device.h"
#include "voxelize/fixed_point_mesh.h"
#include "voxelize/gpu_gate.h"
#include "voxelize/triangle_bins.h"

namespace voxd::detail {
namespace {

// The kernels' passes on the CPU, with the per-thread code they run: the
// crossings of each (row, binned triangle) pair, counted, then written to
// their columns' segments in triangle order (not the columns' final order:
// the column pass sorts them, as on the GPU, where they arrive in any
// order), then each column filled. Parallel over rows, since the tests run
// it on grids of millions of voxels.
class HostCoverageDevice final : public CoverageSlabDevice {
 public:
  explicit HostCoverageDevice(int threads) : threads_(threads) {}

  void begin(const CoverageScene& scene, std::int64_t, std::uint64_t crossing_room) override {
    scene_ = &scene;
    room_ = crossing_room;
  }

  void count(std::int64_t k0, std::int64_t layers, std::uint32_t* counts) override {
    const std::int64_t ny = scene_->columns.ny;
    std::fill(counts, counts + layers * ny, 0u);
    parallel_for(0, layers, 1, threads_, [&](std::int64_t a, std::int64_t b) {
      for (std::int64_t k = a; k < b; ++k)
        cross_row(k0 + k, [&](std::int64_t j, int, double) { ++counts[k * ny + j]; });
    });
  }

  void fill(std::int64_t k0, std::int64_t layers, const std::uint64_t* offsets, float* out) override {
    const std::int64_t nx = scene_->columns.nx, ny = scene_->columns.ny;
    // What a GPU could not hold, the emulation refuses too.
    if (offsets[layers * ny] > room_) throw std::logic_error("coverage: a fill past the crossings' room");
    entries_.resize(offsets[layers * ny]);
    parallel_for(0, layers, 1, threads_, [&](std::int64_t a, std::int64_t b) {
      std::vector<std::uint64_t> cursor(static_cast<std::size_t>(ny));
      for (std::int64_t k = a; k < b; ++k) {
        const std::uint64_t* row_offsets = offsets + k * ny;
        std::copy(row_offsets, row_offsets + ny, cursor.begin());
        cross_row(k0 + k, [&](std::int64_t j, int ray, double x) {
          entries_[cursor[static_cast<std::size_t>(j)]++] = {x, ray, 0.0f};
        });
        for (std::int64_t j = 0; j < ny; ++j) {
          float* row = out + (k * ny + j) * nx;
          std::fill(row, row + nx, 0.0f);
          fill_coverage_column(entries_.data() + row_offsets[j], static_cast<std::int64_t>(row_offsets[j + 1] - row_offsets[j]),
                               scene_->columns, row);
        }
      }
    });
  }

 private:
  // emit(j, ray, x) for every crossing of row k's rays.
  template <typename Emit>
  void cross_row(std::int64_t k, Emit&& emit) const {
    const CoverageScene& s = *scene_;
    const auto chunk = static_cast<std::size_t>(k / s.rows_per_chunk);
    for (std::uint32_t i = s.bin_offsets[chunk]; i < s.bin_offsets[chunk + 1]; ++i) {
      const std::uint32_t* corner = &s.triangles[3 * static_cast<std::size_t>(s.bin_triangles[i])];
      cross_row_triangle(&s.vertices[3 * static_cast<std::size_t>(corner[0])],
                         &s.vertices[3 * static_cast<std::size_t>(corner[1])],
                         &s.vertices[3 * static_cast<std::size_t>(corner[2])], k, s.columns.ny, s.rays, 0, 1, emit);
    }
  }

  int threads_;
  const CoverageScene* scene_ = nullptr;
  std::uint64_t room_ = 0;
  std::vector<ColumnEntry> entries_;
};

// The mesh in fixed point and binned by single rows (a GPU block takes a
// row's triangles, so none of them is for another row), and the rays.
std::unique_ptr<const CoverageScene> make_coverage_scene(const Mesh& mesh, const Grid& grid,
                                                         const CoverageOptions& options, int threads) {
  auto scene = std::make_unique<CoverageScene>();
  const FixedMesh fixed(mesh, grid);
  // Rays of row k sit within half a voxel of its centre: margin 1.
  TriangleBins bins = bin_triangles(fixed, 2, grid.dims.z, 1, 1, threads);
  // Only the vertices of binned triangles: the CPU path never quantizes
  // the others either (nor refuses one absurdly far from the grid).
  scene->vertices.assign(3 * mesh.vertices.size(), 0);
  std::vector<bool> done(mesh.vertices.size(), false);
  for (const std::uint32_t t : bins.triangles)
    for (const std::uint32_t v : mesh.triangles[t]) {
      if (done[v]) continue;
      done[v] = true;
      const FixedPoint p = fixed.vertex(v);
      std::copy(p.begin(), p.end(), scene->vertices.begin() + 3 * static_cast<std::ptrdiff_t>(v));
    }
  scene->triangles.reserve(3 * mesh.triangles.size());
  for (const auto& t : mesh.triangles) scene->triangles.insert(scene->triangles.end(), t.begin(), t.end());
  scene->rows_per_chunk = bins.rows_per_chunk;
  scene->bin_offsets = std::move(bins.offsets);
  scene->bin_triangles = std::move(bins.triangles);
  scene->rays = coverage_ray_pattern(options);
  scene->columns.nx = grid.dims.x;
  scene->columns.ny = grid.dims.y;
  scene->columns.weight = 1.0f / static_cast<float>(options.rays * options.rays);
  scene->columns.points = options.sampling == CoverageSampling::uniform ? options.points : 0;
  return scene;
}

// Slabs of up to max_layers layers, each written where begin_slab(k0, n)
// says and handed to end_slab(k0, n) when final.
template <typename BeginSlab, typename EndSlab>
void coverage_slabs(CoverageBackend backend, const Mesh& mesh, const Grid& grid, const CoverageOptions& options,
                    std::int64_t max_layers, const BeginSlab& begin_slab, const EndSlab& end_slab,
                    JobControl* control, CoverageRunReport* report) {
  if (backend == CoverageBackend::cuda && !cuda_unavailable_reason().empty())
    throw Error(ErrorCode::invalid_argument, cuda_unavailable_reason());
  const int threads = options.threads > 0 ? options.threads : default_thread_count();
  const auto scene = make_coverage_scene(mesh, grid, options, threads);
  const std::int64_t nx = grid.dims.x, ny = grid.dims.y, nz = grid.dims.z;

  std::unique_lock<std::mutex> gate;
  std::unique_ptr<CoverageSlabDevice> device;
  std::uint64_t budget = options.gpu_memory;
  if (backend == CoverageBackend::cuda) {
    gate = std::unique_lock<std::mutex>(gpu_gate());
    device = make_cuda_coverage_device(budget);
  } else {
    device = std::make_unique<HostCoverageDevice>(threads);
    if (budget == 0)
      budget = scene->bytes() + 8 + 2 * coverage_layer_bytes(grid) * static_cast<std::uint64_t>(nz) +
               (std::uint64_t{1} << 26) * coverage_crossing_bytes();
  }
  const CoverageSlabPlan plan = plan_coverage_slabs(grid, scene->bytes(), budget);
  const std::int64_t layers = std::min(plan.layers_per_slab, std::max<std::int64_t>(max_layers, 1));
  device->begin(*scene, layers, plan.crossing_room);
  std::vector<std::uint32_t> counts(static_cast<std::size_t>(layers * ny));
  std::vector<std::uint64_t> offsets(static_cast<std::size_t>(layers * ny + 1));
  std::int64_t slabs = 0, passes = 0;
  for (std::int64_t k0 = 0; k0 < nz; k0 += layers, ++slabs) {
    if (control) control->check_cancelled();
    const std::int64_t n = std::min(layers, nz - k0);
    device->count(k0, n, counts.data());
    float* out = begin_slab(k0, n);
    // Groups of whole rows whose crossings fit the room.
    for (std::int64_t first = 0; first < n;) {
      std::int64_t last = first;
      std::uint64_t total = 0;
      for (; last < n; ++last) {
        std::uint64_t row = 0;
        for (std::int64_t c = last * ny; c < (last + 1) * ny; ++c) row += counts[static_cast<std::size_t>(c)];
        if (total + row > plan.crossing_room) {
          if (last == first)
            throw Error(ErrorCode::limit_exceeded,
                        "row " + std::to_string(k0 + last) + " of the grid has " + std::to_string(row) +
                            " crossings of its rays (" + std::to_string(row * coverage_crossing_bytes()) +
                            " bytes); the GPU memory budget of " + std::to_string(budget) + " bytes leaves room for " +
                            std::to_string(plan.crossing_room) +
                            " beside the mesh and the slab; raise the budget, lower the rays or use device cpu");
          break;
        }
        total += row;
      }
      std::uint64_t sum = 0;
      for (std::int64_t c = first * ny; c < last * ny; ++c) {
        offsets[static_cast<std::size_t>(c - first * ny)] = sum;
        sum += counts[static_cast<std::size_t>(c)];
      }
      offsets[static_cast<std::size_t>((last - first) * ny)] = sum;
      device->fill(k0 + first, last - first, offsets.data(), out + first * nx * ny);
      ++passes;
      first = last;
      if (control) control->check_cancelled();
    }
    end_slab(k0, n);
    if (control) control->set_progress(static_cast<double>(k0 + n) / static_cast<double>(nz));
  }
  if (report) {
    report->device = backend == CoverageBackend::cuda ? ComputeDevice::cuda : ComputeDevice::cpu;
    report->slabs = slabs;
    report->passes = passes;
    report->gpu_bytes = plan.device_bytes;
    report->gpu_kernel_ms = device->kernel_ms();
    report->gpu_copy_ms = device->copy_ms();
    report->gpu_measured_bytes = device->measured_bytes();
  }
}

}  // namespace

std::uint64_t coverage_layer_bytes(const Grid& grid) {
  const auto nx = static_cast<std::uint64_t>(grid.dims.x), ny = static_cast<std::uint64_t>(grid.dims.y);
  return nx * ny * sizeof(float) + ny * (sizeof(std::uint32_t) + sizeof(std::uint64_t));
}

std::uint64_t coverage_crossing_bytes() { return sizeof(ColumnEntry); }

std::uint64_t coverage_scene_bytes(const Mesh& mesh, const Grid& grid) {
  return grid.voxel_count() == 0 ? 0 : make_coverage_scene(mesh, grid, CoverageOptions{}, default_thread_count())->bytes();
}

CoverageSlabPlan plan_coverage_slabs(const Grid& grid, std::uint64_t scene_bytes, std::uint64_t budget) {
  CoverageSlabPlan plan;
  const std::int64_t nz = grid.dims.z;
  if (grid.voxel_count() == 0) return plan;
  const std::uint64_t layer = coverage_layer_bytes(grid);
  const std::uint64_t fixed = scene_bytes + sizeof(std::uint64_t);  // the scene and the offsets' total
  if (budget < fixed || (budget - fixed) / layer < 1)
    throw Error(ErrorCode::limit_exceeded,
                "the GPU memory budget of " + std::to_string(budget) + " bytes cannot hold the mesh (" +
                    std::to_string(scene_bytes) + " bytes) and one z layer of the " + std::to_string(grid.dims.x) +
                    " x " + std::to_string(grid.dims.y) + " grid (" + std::to_string(layer) +
                    " bytes); raise the budget or use device cpu");
  const std::uint64_t room = budget - fixed;
  plan.layers_per_slab = static_cast<std::int64_t>(
      std::clamp<std::uint64_t>(room / 2 / layer, 1, static_cast<std::uint64_t>(nz)));
  plan.slabs = (nz + plan.layers_per_slab - 1) / plan.layers_per_slab;
  plan.crossing_room = (room - static_cast<std::uint64_t>(plan.layers_per_slab) * layer) / coverage_crossing_bytes();
  plan.device_bytes = fixed + static_cast<std::uint64_t>(plan.layers_per_slab) * layer +
                      plan.crossing_room * coverage_crossing_bytes();
  return plan;
}

DenseVolume<float> voxelize_coverage_on(CoverageBackend backend, const Mesh& mesh, const Grid& grid,
                                        const CoverageOptions& options, JobControl* control,
                                        CoverageRunReport* report) {
  validate(options);
  if (grid.voxel_count() == 0) {
    if (report) *report = CoverageRunReport{};
    return DenseVolume<float>(grid, 0.0f);
  }
  // Every voxel is written by its column's pass.
  DenseVolume<float> out(grid, DenseVolume<float>::Uninitialized{});
  coverage_slabs(
      backend, mesh, grid, options, grid.dims.z, [&](std::int64_t k0, std::int64_t) { return out.slab(k0); },
      [](std::int64_t, std::int64_t) {}, control, report);
  return out;
}

void voxelize_coverage_streamed_on(CoverageBackend backend, const Mesh& mesh, const Grid& grid,
                                   const CoverageOptions& options, std::int64_t slab_layers,
                                   const CoverageSlabConsumer& consume, JobControl* control,
                                   CoverageRunReport* report) {
  validate(options);
  if (grid.voxel_count() == 0) {
    if (report) *report = CoverageRunReport{};
    return;
  }
  // One slab's memory, reused (see voxelize_coverage_streamed); the last,
  // shorter slab is one of its own size.
  std::optional<DenseVolume<float>> slab;
  coverage_slabs(
      backend, mesh, grid, options, std::clamp<std::int64_t>(slab_layers, 1, grid.dims.z),
      [&](std::int64_t k0, std::int64_t n) {
        if (!slab || slab->grid().dims.z != n)
          slab.emplace(slab_grid(grid, k0, n), DenseVolume<float>::Uninitialized{});
        else
          slab->move_to(slab_grid(grid, k0, n));
        return slab->values().data();
      },
      [&](std::int64_t k0, std::int64_t) { consume(k0, *slab); }, control, report);
}

}  // namespace voxd::detail
