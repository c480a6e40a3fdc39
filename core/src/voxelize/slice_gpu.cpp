// The slice functions' colours made slab by slab on a device: the CUDA GPU,
// or the host emulation of its kernel. See voxd/detail/slice_gpu.h.
#include "voxd/detail/slice_gpu.h"

#include <algorithm>
#include <mutex>
#include <string>

#include "voxd/compute_device.h"
#include "voxd/error.h"
#include "voxd/parallel.h"
#include "voxd/voxelize/voxelize.h"
#include "voxelize/gpu_gate.h"
#include "voxelize/slice_device.h"

namespace voxd::detail {
namespace {

static_assert(sizeof(ShadeColour) == sizeof(Rgba8) && alignof(ShadeColour) == alignof(Rgba8),
              "the device writes colours straight into the volume's voxels");

// The kernel's loop on the CPU: every voxel of the slab through
// colour_slab_voxel, the function the kernel's threads run, with the tables
// where the host keeps them. Parallel over the slab's rows, since the tests
// run it on grids of millions of voxels.
class HostSlabDevice final : public SliceSlabDevice {
 public:
  explicit HostSlabDevice(int threads) : threads_(threads) {}

  void begin(const SliceShading& shading, const SlabShape& shape, std::int64_t) override {
    shading_ = &shading;
    shape_ = shape;
  }

  void colour(const std::uint64_t* bits, std::int64_t k0, std::int64_t layers, ShadeColour* out) override {
    const std::int64_t rows = shape_.ny * layers;
    parallel_for(0, rows, 64, threads_, [&](std::int64_t r0, std::int64_t r1) {
      for (std::int64_t index = r0 * shape_.nx; index < r1 * shape_.nx; ++index)
        colour_slab_voxel(shading_->params, shading_->frame, bits, shape_.row_words, shape_.nx, shape_.ny, k0,
                          index, out);
    });
  }

 private:
  int threads_;
  const SliceShading* shading_ = nullptr;
  SlabShape shape_;
};

}  // namespace

std::uint64_t slice_layer_bytes(const Grid& grid) {
  const auto nx = static_cast<std::uint64_t>(grid.dims.x), ny = static_cast<std::uint64_t>(grid.dims.y);
  const std::uint64_t row_words = (nx + 63) / 64;
  return ny * row_words * 8 + nx * ny * sizeof(ShadeColour);
}

SliceSlabPlan plan_slice_slabs(const Grid& grid, std::uint64_t table_bytes, std::uint64_t budget) {
  SliceSlabPlan plan;
  const std::int64_t nz = grid.dims.z;
  if (grid.voxel_count() == 0) return plan;
  const std::uint64_t layer = slice_layer_bytes(grid);
  if (budget < table_bytes || (budget - table_bytes) / layer < 1)
    throw Error(ErrorCode::limit_exceeded,
                "the GPU memory budget of " + std::to_string(budget) + " bytes cannot hold one z layer of the " +
                    std::to_string(grid.dims.x) + " x " + std::to_string(grid.dims.y) + " grid (" +
                    std::to_string(layer + table_bytes) +
                    " bytes with the function's tables); raise the budget or use device cpu");
  const std::uint64_t fit = (budget - table_bytes) / layer;
  plan.layers_per_slab = static_cast<std::int64_t>(std::min<std::uint64_t>(fit, static_cast<std::uint64_t>(nz)));
  plan.slabs = (nz + plan.layers_per_slab - 1) / plan.layers_per_slab;
  plan.device_bytes = table_bytes + static_cast<std::uint64_t>(plan.layers_per_slab) * layer;
  return plan;
}

DenseVolume<Rgba8> voxelize_slice_on(SliceBackend backend, const Mesh& mesh, const Grid& grid,
                                     const SliceOptions& options, JobControl* control, SliceRunReport* report) {
  validate(options);
  const auto shading = make_slice_shading(options, make_slice_frame(mesh, options.axis), grid);
  // Fail before the solid is made: a GPU asked for and missing, or a budget
  // given that cannot hold a layer, is the user's to fix, not worth a
  // wasted voxelization.
  if (backend == SliceBackend::cuda && !cuda_unavailable_reason().empty())
    throw Error(ErrorCode::invalid_argument, cuda_unavailable_reason());
  if (options.gpu_memory > 0) plan_slice_slabs(grid, shading->table_bytes(), options.gpu_memory);

  const BitVolume solid = [&] {
    const NestedSpan first_half(control, 0.0, 0.5);
    return voxelize(mesh, grid, {VoxelMode::solid, options.inside, options.threads}, control);
  }();
  const NestedSpan second_half(control, 0.5, 1.0);

  // The GPU is held only for the colours: another job's solid is made
  // meanwhile. Its budget is read from the memory free now.
  std::unique_lock<std::mutex> gate;
  std::unique_ptr<SliceSlabDevice> device;
  std::uint64_t budget = options.gpu_memory;
  if (backend == SliceBackend::cuda) {
    gate = std::unique_lock<std::mutex>(gpu_gate());
    device = make_cuda_slab_device(budget);
  } else {
    device = std::make_unique<HostSlabDevice>(options.threads > 0 ? options.threads : default_thread_count());
    if (budget == 0) budget = shading->table_bytes() + slice_layer_bytes(grid) * static_cast<std::uint64_t>(grid.dims.z);
  }
  const SliceSlabPlan plan = plan_slice_slabs(grid, shading->table_bytes(), budget);
  DenseVolume<Rgba8> out(grid);
  if (plan.slabs > 0) {
    device->begin(*shading, {grid.dims.x, grid.dims.y, solid.row_words()}, plan.layers_per_slab);
    for (std::int64_t k0 = 0; k0 < grid.dims.z; k0 += plan.layers_per_slab) {
      if (control) control->check_cancelled();
      const std::int64_t layers = std::min(plan.layers_per_slab, grid.dims.z - k0);
      device->colour(solid.slab(k0), k0, layers, reinterpret_cast<ShadeColour*>(out.slab(k0)));
      if (control) control->set_progress(static_cast<double>(k0 + layers) / static_cast<double>(grid.dims.z));
    }
  }
  if (report) {
    report->device = backend == SliceBackend::cuda ? ComputeDevice::cuda : ComputeDevice::cpu;
    report->slabs = plan.slabs;
    report->passes = plan.slabs;  // a kernel pass a slab
    report->gpu_bytes = plan.device_bytes;
    report->gpu_kernel_ms = device->kernel_ms();
    report->gpu_copy_ms = device->copy_ms();
    report->gpu_measured_bytes = device->measured_bytes();
  }
  return out;
}

}  // namespace voxd::detail
