#pragma once
// The slice functions' GPU path, opened for the tests and benchmarks: how a
// grid is split into slabs that fit the GPU's memory, and the slab loop run
// either on the CUDA GPU or on a host emulation of the kernel (the same
// shading code, core/src/voxelize/slice_shading.h, run on the CPU), so the
// splitting, the tables and the copies are tested on machines without a GPU.
#include <cstdint>

#include "voxd/dense_volume.h"
#include "voxd/grid.h"
#include "voxd/mesh.h"
#include "voxd/progress.h"
#include "voxd/voxelize/slice_functions.h"

namespace voxd::detail {

// How the colouring of a grid is split into slabs of whole z layers.
struct SliceSlabPlan {
  std::int64_t layers_per_slab = 0;
  std::int64_t slabs = 0;
  // What the device holds at once: the function's tables, the solid's
  // words of one slab and its colours (4 bytes a voxel).
  std::uint64_t device_bytes = 0;
};

// Bytes a layer of `grid` takes on the device (its solid's words and colours).
std::uint64_t slice_layer_bytes(const Grid& grid);
// The deepest slabs whose tables and one slab fit in `budget` bytes, at
// most the whole grid. Throws Error(limit_exceeded), saying how much a
// single layer needs, when not even one layer fits.
SliceSlabPlan plan_slice_slabs(const Grid& grid, std::uint64_t table_bytes, std::uint64_t budget);

enum class SliceBackend { cuda, host_emulation };

// voxelize_slice with its colours made slab by slab on `backend`, whatever
// options.device says; options.gpu_memory is the budget (0: 3/4 of the
// GPU's free memory; the whole grid for the emulation). Throws as
// voxelize_slice does, and Error(invalid_argument) for cuda where
// cuda_unavailable_reason() is not empty.
DenseVolume<Rgba8> voxelize_slice_on(SliceBackend backend, const Mesh& mesh, const Grid& grid,
                                     const SliceOptions& options, JobControl* control = nullptr,
                                     SliceRunReport* report = nullptr);

}  // namespace voxd::detail
