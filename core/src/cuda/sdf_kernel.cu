// The signed distance field's band on a CUDA GPU: a block a brick of 8^3
// voxels, a thread a voxel; the brick's triangles go through shared memory
// in tiles, and each voxel keeps the least exact distance over them, by the
// code of core/src/voxelize/sdf_band_kernels.h the CPU runs too, built with
// -fmad=false (core/CMakeLists.txt) so that every float equals the CPU's.
#include <cuda_runtime.h>

#include <algorithm>

#include "cuda/cuda_support.h"
#include "voxd/compute_device.h"
#include "voxd/error.h"
#include "voxelize/sdf_device.h"

namespace voxd::sdf {
namespace {

using detail::cuda::check;
using detail::cuda::DeviceBuffer;

constexpr int kThreads = kBrick * kBrick * kBrick;
constexpr int kTile = 32;  // triangles staged at once: 8 KB of shared memory

__global__ void prepare_kernel(const float* vertices, const std::uint32_t* corners, std::int64_t count,
                               DeviceTriangle* triangles) {
  const std::int64_t stride = static_cast<std::int64_t>(gridDim.x) * blockDim.x;
  for (std::int64_t t = static_cast<std::int64_t>(blockIdx.x) * blockDim.x + threadIdx.x; t < count; t += stride) {
    const std::uint32_t* v = corners + 3 * t;
    triangles[t] = device_triangle(vertices + 3 * static_cast<std::size_t>(v[0]),
                                   vertices + 3 * static_cast<std::size_t>(v[1]),
                                   vertices + 3 * static_cast<std::size_t>(v[2]));
  }
}

// Bricks of z layers [k0, k0 + layers): blockIdx.x numbers them x fastest.
__global__ void band_kernel(SdfBandParams p, const DeviceTriangle* triangles, const std::uint64_t* brick_offsets,
                            const std::uint32_t* brick_triangles, std::int64_t k0, std::int64_t layers, float* out) {
  __shared__ alignas(16) unsigned char raw[kTile * sizeof(DeviceTriangle)];
  DeviceTriangle* tile = reinterpret_cast<DeviceTriangle*>(raw);
  const std::int64_t per_layer = p.bricks[0] * p.bricks[1];
  const std::int64_t item = blockIdx.x;
  const std::int64_t bx = item % p.bricks[0], by = item / p.bricks[0] % p.bricks[1], bz = k0 / kBrick + item / per_layer;
  const std::int64_t i = bx * kBrick + threadIdx.x % kBrick, j = by * kBrick + threadIdx.x / kBrick % kBrick,
                     k = bz * kBrick + threadIdx.x / (kBrick * kBrick);
  const bool mine = i < p.dims[0] && j < p.dims[1] && k < k0 + layers;
  const Vec3d centre = voxel_centre(p, i, j, k);
  const auto brick = static_cast<std::size_t>(bx + p.bricks[0] * (by + p.bricks[1] * bz));
  const std::uint64_t begin = brick_offsets[brick], end = brick_offsets[brick + 1];
  double best = HUGE_VAL;
  for (std::uint64_t x = begin; x < end; x += kTile) {
    const int count = static_cast<int>(end - x < kTile ? end - x : kTile);
    if (static_cast<int>(threadIdx.x) < count) tile[threadIdx.x] = triangles[brick_triangles[x + threadIdx.x]];
    __syncthreads();
    if (mine) best = nearest2(tile, count, centre, best);
    __syncthreads();
  }
  if (mine) out[((k - k0) * p.dims[1] + j) * p.dims[0] + i] = band_value(p, best);
}

class CudaBandDevice final : public SdfBandDevice {
 public:
  void begin(const SdfBandScene& scene, std::int64_t max_layers) override {
    params_ = scene.params;
    const std::size_t count = scene.triangles.size() / 3;
    vertices_.allocate(scene.vertices.size(), "allocation of the vertices");
    corners_.allocate(scene.triangles.size(), "allocation of the triangles");
    triangles_.allocate(count, "allocation of the prepared triangles");
    offsets_.allocate(scene.brick_offsets.size(), "allocation of the bricks");
    lists_.allocate(scene.brick_triangles.size(), "allocation of the bricks' triangles");
    out_.allocate(static_cast<std::size_t>(max_layers * params_.dims[0] * params_.dims[1]), "allocation of the slab");
    memory_.sample();
    stream_.timed(false, "copy of the mesh", [&] {
      vertices_.upload(scene.vertices.data(), scene.vertices.size(), stream_.get(), "copy of the vertices");
      corners_.upload(scene.triangles.data(), scene.triangles.size(), stream_.get(), "copy of the triangles");
      offsets_.upload(scene.brick_offsets.data(), scene.brick_offsets.size(), stream_.get(), "copy of the bricks");
      lists_.upload(scene.brick_triangles.data(), scene.brick_triangles.size(), stream_.get(), "copy of the bricks");
    });
    if (count > 0)
      stream_.timed(true, "preparing the triangles", [&] {
        const auto blocks = static_cast<unsigned>(std::min<std::size_t>((count + 255) / 256, 1 << 16));
        prepare_kernel<<<blocks, 256, 0, stream_.get()>>>(vertices_.data, corners_.data,
                                                          static_cast<std::int64_t>(count), triangles_.data);
      });
  }

  void band(std::int64_t k0, std::int64_t layers, float* out) override {
    const std::int64_t bricks = params_.bricks[0] * params_.bricks[1] * ((layers + kBrick - 1) / kBrick);
    const std::size_t values = static_cast<std::size_t>(layers * params_.dims[0] * params_.dims[1]);
    stream_.timed(true, "the band kernel", [&] {
      band_kernel<<<static_cast<unsigned>(bricks), kThreads, 0, stream_.get()>>>(
          params_, triangles_.data, offsets_.data, lists_.data, k0, layers, out_.data);
    });
    stream_.timed(false, "copy of the band", [&] {
      check(cudaMemcpyAsync(out, out_.data, values * sizeof(float), cudaMemcpyDeviceToHost, stream_.get()),
            "copy of the band");
    });
  }

  double kernel_ms() const override { return stream_.kernel_ms(); }
  double copy_ms() const override { return stream_.copy_ms(); }
  std::uint64_t measured_bytes() const override { return memory_.peak(); }

 private:
  detail::cuda::MemoryWatch memory_;  // first: the free memory before any allocation
  detail::cuda::TimedStream stream_;
  SdfBandParams params_;
  DeviceBuffer<float> vertices_;
  DeviceBuffer<std::uint32_t> corners_, lists_;
  DeviceBuffer<DeviceTriangle> triangles_;
  DeviceBuffer<std::uint64_t> offsets_;
  DeviceBuffer<float> out_;
};

}  // namespace

std::unique_ptr<SdfBandDevice> make_cuda_sdf_device(std::uint64_t& budget) {
  if (const std::string& why = cuda_unavailable_reason(); !why.empty()) throw Error(ErrorCode::invalid_argument, why);
  detail::cuda::select_gpu(budget);
  return std::make_unique<CudaBandDevice>();
}

}  // namespace voxd::sdf
