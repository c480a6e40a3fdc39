#pragma once
// What the slice functions' slab loop needs of a place to colour slabs: the
// CUDA GPU (core/src/cuda/slice_kernel.cu) or the host emulation of its
// kernel (slice_gpu.cpp). Plain types only: nvcc compiles the CUDA side.
#include <cstdint>
#include <memory>
#include <vector>

#include "voxelize/slice_shading.h"

namespace voxd {
struct Grid;
struct SliceFrame;
struct SliceOptions;
}  // namespace voxd

namespace voxd::detail {

// A slice function ready to evaluate: its numbers, with the tables they
// point to kept here (on the host), and where voxel centres lie.
struct SliceShading {
  SliceShadeParams params;
  SliceVoxelFrame frame;
  std::vector<ShadeRampStop> ramp;
  std::vector<ShadeColour> lookup;
  std::vector<std::uint8_t> perm;

  SliceShading() = default;
  SliceShading(const SliceShading&) = delete;
  SliceShading& operator=(const SliceShading&) = delete;
  // Bytes of the tables (what a device copies besides the slabs).
  std::uint64_t table_bytes() const {
    return ramp.size() * sizeof(ShadeRampStop) + lookup.size() * sizeof(ShadeColour) + perm.size();
  }
};

// The shading of validated options on `frame`, for voxels of `grid`
// (slice_functions.cpp).
std::unique_ptr<const SliceShading> make_slice_shading(const SliceOptions& options, const SliceFrame& frame,
                                                       const Grid& grid);

// The shape of a grid's slabs.
struct SlabShape {
  std::int64_t nx = 0, ny = 0, row_words = 0;
};

class SliceSlabDevice {
 public:
  virtual ~SliceSlabDevice() = default;
  // Takes the function (copying its tables) and makes room for slabs of
  // up to `max_layers` layers.
  virtual void begin(const SliceShading& shading, const SlabShape& shape, std::int64_t max_layers) = 0;
  // Colours layers [k0, k0 + layers): `bits` holds their solid's rows,
  // `out` receives their voxels, x fastest.
  virtual void colour(const std::uint64_t* bits, std::int64_t k0, std::int64_t layers, ShadeColour* out) = 0;
  // Milliseconds spent in kernels and in copies so far (0 on the host).
  virtual double kernel_ms() const { return 0.0; }
  virtual double copy_ms() const { return 0.0; }
  // The device memory its allocations took, measured (0 on the host): what
  // the plan's estimate is checked against.
  virtual std::uint64_t measured_bytes() const { return 0; }
};

// The CUDA GPU (device 0), with `budget` bytes of its memory at most (0:
// three quarters of what is free now): throws Error(invalid_argument)
// with cuda_unavailable_reason() where there is none. Sets `budget` to
// the budget it chose.
std::unique_ptr<SliceSlabDevice> make_cuda_slab_device(std::uint64_t& budget);

}  // namespace voxd::detail
