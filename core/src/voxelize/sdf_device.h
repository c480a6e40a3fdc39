#pragma once
// What the band's slab loop (sdf_gpu.cpp) needs of a place to compute it:
// the CUDA GPU (core/src/cuda/sdf_kernel.cu) or the host emulation of its
// kernel (sdf_gpu.cpp). Both run sdf_band_kernels.h.
#include <cstdint>
#include <memory>
#include <vector>

#include "voxelize/sdf_band_kernels.h"

namespace voxd::sdf {

// The mesh and the bricks as the kernel reads them, made once on the host.
struct SdfBandScene {
  std::vector<float> vertices;            // x, y, z of every vertex
  std::vector<std::uint32_t> triangles;   // three vertex indices each
  // Brick b's triangles: brick_triangles[brick_offsets[b] .. brick_offsets[b + 1]),
  // bricks numbered x fastest.
  std::vector<std::uint64_t> brick_offsets;
  std::vector<std::uint32_t> brick_triangles;
  SdfBandParams params;

  SdfBandScene() = default;
  SdfBandScene(const SdfBandScene&) = delete;
  SdfBandScene& operator=(const SdfBandScene&) = delete;
  // Bytes a device holds of it, with the triangles it prepares from it.
  std::uint64_t bytes() const {
    return vertices.size() * sizeof(float) + triangles.size() * sizeof(std::uint32_t) +
           brick_offsets.size() * sizeof(std::uint64_t) + brick_triangles.size() * sizeof(std::uint32_t) +
           triangles.size() / 3 * sizeof(DeviceTriangle);
  }
};

class SdfBandDevice {
 public:
  virtual ~SdfBandDevice() = default;
  // Takes the scene (copying it, and preparing its triangles) and makes
  // room for slabs of up to `max_layers` z layers (a multiple of kBrick).
  virtual void begin(const SdfBandScene& scene, std::int64_t max_layers) = 0;
  // The unsigned band values of layers [k0, k0 + layers) (k0 a multiple of
  // kBrick) into `out`, x fastest, every voxel written.
  virtual void band(std::int64_t k0, std::int64_t layers, float* out) = 0;
  virtual double kernel_ms() const { return 0.0; }
  virtual double copy_ms() const { return 0.0; }
  virtual std::uint64_t measured_bytes() const { return 0; }
};

// The CUDA GPU (device 0), with `budget` bytes of its memory at most (0:
// three quarters of what is free now): throws Error(invalid_argument) with
// cuda_unavailable_reason() where there is none. Sets `budget`.
std::unique_ptr<SdfBandDevice> make_cuda_sdf_device(std::uint64_t& budget);

}  // namespace voxd::sdf
