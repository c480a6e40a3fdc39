#pragma once
// What grey coverage's slab loop (coverage_gpu.cpp) needs of a place to
// compute slabs: the CUDA GPU (core/src/cuda/coverage_kernel.cu) or the host
// emulation of its kernels (coverage_gpu.cpp). Both run the passes of
// voxelize/coverage_kernels.h.
#include <cstdint>
#include <memory>
#include <vector>

#include "voxelize/coverage_kernels.h"

namespace voxd {
struct CoverageOptions;
}  // namespace voxd

namespace voxd::detail {

// The rays of validated options (coverage.cpp).
CoverageRayPattern coverage_ray_pattern(const CoverageOptions& options);

// The mesh as the kernels read it, and the rays: prepared once on the host.
struct CoverageScene {
  // Fixed-point corners {x, y, z} of every vertex a binned triangle uses
  // (the others are 0), and the triangles' vertex indices, three each.
  std::vector<std::int64_t> vertices;
  std::vector<std::uint32_t> triangles;
  // Triangles binned by chunks of rows_per_chunk rows (voxelize/triangle_bins.h):
  // chunk c's are bin_triangles[bin_offsets[c] .. bin_offsets[c + 1]).
  std::vector<std::uint32_t> bin_offsets, bin_triangles;
  std::int64_t rows_per_chunk = 1;
  CoverageRayPattern rays;
  CoverageColumnParams columns;

  CoverageScene() = default;
  CoverageScene(const CoverageScene&) = delete;
  CoverageScene& operator=(const CoverageScene&) = delete;
  // Bytes a device holds of it.
  std::uint64_t bytes() const {
    return (vertices.size() * sizeof(std::int64_t)) +
           (triangles.size() + bin_offsets.size() + bin_triangles.size()) * sizeof(std::uint32_t);
  }
};

class CoverageSlabDevice {
 public:
  virtual ~CoverageSlabDevice() = default;
  // Takes the scene (copying it) and makes room for slabs of up to
  // `max_layers` layers, whose fills hold at most `crossing_room` crossings.
  virtual void begin(const CoverageScene& scene, std::int64_t max_layers, std::uint64_t crossing_room) = 0;
  // The crossings of each column of rows [k0, k0 + layers): counts[(k - k0)
  // * ny + j] for column j of row k.
  virtual void count(std::int64_t k0, std::int64_t layers, std::uint32_t* counts) = 0;
  // Rows [k0, k0 + layers) into `out` (x fastest, every voxel written):
  // offsets[c] is where column c's crossings start among the rows', by
  // count()'s numbers, and offsets[columns] their total.
  virtual void fill(std::int64_t k0, std::int64_t layers, const std::uint64_t* offsets, float* out) = 0;
  // Milliseconds spent in kernels and in copies so far (0 on the host).
  virtual double kernel_ms() const { return 0.0; }
  virtual double copy_ms() const { return 0.0; }
  // The most device memory its allocations took at once, measured (0 on
  // the host): what the plan's estimate is checked against.
  virtual std::uint64_t measured_bytes() const { return 0; }
};

// The CUDA GPU (device 0), with `budget` bytes of its memory at most (0:
// three quarters of what is free now): throws Error(invalid_argument)
// with cuda_unavailable_reason() where there is none. Sets `budget` to
// the budget it chose.
std::unique_ptr<CoverageSlabDevice> make_cuda_coverage_device(std::uint64_t& budget);

}  // namespace voxd::detail
