#pragma once
// Grey coverage's GPU path, opened for the tests and benchmarks: how a grid
// is split into slabs and groups of rows that fit the GPU's memory, and the
// slab loop run either on the CUDA GPU or on a host emulation of its kernels
// (the same per-thread code, core/src/voxelize/coverage_kernels.h, run on
// the CPU), so the splitting, the scene and the kernels' arithmetic are
// tested on machines without a GPU.
#include <cstdint>

#include "voxd/dense_volume.h"
#include "voxd/grid.h"
#include "voxd/mesh.h"
#include "voxd/progress.h"
#include "voxd/voxelize/coverage.h"

namespace voxd::detail {

// How the coverage of a grid is split on the device.
struct CoverageSlabPlan {
  std::int64_t layers_per_slab = 0;
  std::int64_t slabs = 0;
  // Room for the crossings of one group of rows, in crossings: rows whose
  // crossings exceed it are filled in several groups.
  std::uint64_t crossing_room = 0;
  // What the device may hold at once: the scene (fixed-point vertices,
  // triangles, row bins), a slab's floats and column counters and offsets,
  // and the crossings' room.
  std::uint64_t device_bytes = 0;
};

// Bytes a layer of `grid` takes on the device besides its crossings (its
// floats, and a counter and an offset per column), and one crossing's.
std::uint64_t coverage_layer_bytes(const Grid& grid);
std::uint64_t coverage_crossing_bytes();
// Bytes of the mesh as the device holds it (fixed-point vertices, triangles,
// their bins by rows).
std::uint64_t coverage_scene_bytes(const Mesh& mesh, const Grid& grid);
// Half of what `budget` leaves beside the scene for the slab (at most the
// whole grid, at least a layer), the rest for the crossings. Throws
// Error(limit_exceeded), saying how much a layer needs, when the scene and a
// layer do not fit.
CoverageSlabPlan plan_coverage_slabs(const Grid& grid, std::uint64_t scene_bytes, std::uint64_t budget);

enum class CoverageBackend { cuda, host_emulation };

// voxelize_coverage with its slabs computed on `backend`, whatever
// options.device says; options.gpu_memory is the budget (0: 3/4 of the
// GPU's free memory; for the emulation, room for the whole grid and 2^26
// crossings). Throws as voxelize_coverage does, Error(invalid_argument) for
// cuda where cuda_unavailable_reason() is not empty, and
// Error(limit_exceeded) when one row's crossings exceed the budget's room.
DenseVolume<float> voxelize_coverage_on(CoverageBackend backend, const Mesh& mesh, const Grid& grid,
                                        const CoverageOptions& options, JobControl* control = nullptr,
                                        CoverageRunReport* report = nullptr);
// voxelize_coverage_streamed likewise: slabs of at most slab_layers layers.
void voxelize_coverage_streamed_on(CoverageBackend backend, const Mesh& mesh, const Grid& grid,
                                   const CoverageOptions& options, std::int64_t slab_layers,
                                   const CoverageSlabConsumer& consume, JobControl* control = nullptr,
                                   CoverageRunReport* report = nullptr);

}  // namespace voxd::detail
