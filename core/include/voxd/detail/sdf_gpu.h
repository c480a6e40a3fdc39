#pragma once
// The signed distance field's GPU path, opened for the tests and
// benchmarks: how the band is split into slabs that fit the GPU's memory,
// and the field made with its band computed slab by slab either on the CUDA
// GPU or on a host emulation of its kernel (the same per-voxel code,
// core/src/voxelize/sdf_band_kernels.h, run on the CPU), so the bricks, the
// splitting and the arithmetic are tested on machines without a GPU.
#include <cstdint>

#include "voxd/bit_volume.h"
#include "voxd/compute_device.h"
#include "voxd/dense_volume.h"
#include "voxd/grid.h"
#include "voxd/mesh.h"
#include "voxd/progress.h"
#include "voxd/voxelize/sdf.h"

namespace voxd::detail {

// How the band is split on the device: slabs of whole bricks (8 z layers).
struct SdfSlabPlan {
  std::int64_t layers_per_slab = 0;
  std::int64_t slabs = 0;
  // What the device holds at once: the scene (vertices, triangles and their
  // prepared form, the bricks' lists) and a slab's floats.
  std::uint64_t device_bytes = 0;
};

// Bytes a z layer's floats take on the device.
std::uint64_t sdf_layer_bytes(const Grid& grid);
// Bytes of the scene the device holds for `mesh` on `grid` with `options`'
// band.
std::uint64_t sdf_scene_bytes(const Mesh& mesh, const Grid& grid, const SdfOptions& options);
// The deepest slabs of whole bricks that fit in `budget` beside the scene,
// at most the whole grid. Throws Error(limit_exceeded), saying what a brick's
// layers need, when not even they fit.
SdfSlabPlan plan_sdf_slabs(const Grid& grid, std::uint64_t scene_bytes, std::uint64_t budget);

enum class SdfBackend { cuda, host_emulation };

// signed_distance_field with its band made on `backend`, whatever
// options.device says (the solid that signs it, the full field's queries and
// the sign on the CPU); options.gpu_memory is the budget (0: 3/4 of the
// GPU's free memory; the whole grid for the emulation). Throws as
// signed_distance_field does, and Error(invalid_argument) for cuda where
// cuda_unavailable_reason() is not empty.
DenseVolume<float> signed_distance_field_on(SdfBackend backend, const Mesh& mesh, const Grid& grid,
                                            const SdfOptions& options, JobControl* control = nullptr,
                                            BitVolume* solid = nullptr, DeviceRunReport* report = nullptr);

}  // namespace voxd::detail
