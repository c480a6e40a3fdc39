// The slice functions' colours on a CUDA GPU: one thread a voxel, running
// colour_slab_voxel (core/src/voxelize/slice_shading.h), the code the CPU
// runs too. Built with -fmad=false (core/CMakeLists.txt) so no multiply-add
// is fused and the bits equal the CPU's.
#include <cuda_runtime.h>

#include <algorithm>
#include <stdexcept>
#include <string>

#include "voxd/compute_device.h"
#include "voxd/error.h"
#include "cuda/cuda_support.h"
#include "voxelize/slice_device.h"

namespace voxd::detail {
namespace {

__global__ void colour_slab_kernel(SliceShadeParams params, SliceVoxelFrame frame, const std::uint64_t* bits,
                                   std::int64_t row_words, std::int64_t nx, std::int64_t ny, std::int64_t k0,
                                   std::int64_t count, ShadeColour* out) {
  // The noise's table in shared memory: every octave of every voxel reads
  // eight scattered entries of it.
  __shared__ std::uint8_t perm[512];
  for (int i = threadIdx.x; i < 512; i += blockDim.x) perm[i] = params.perm[i];
  __syncthreads();
  params.perm = perm;
  const std::int64_t stride = static_cast<std::int64_t>(gridDim.x) * blockDim.x;
  for (std::int64_t index = static_cast<std::int64_t>(blockIdx.x) * blockDim.x + threadIdx.x; index < count;
       index += stride)
    colour_slab_voxel(params, frame, bits, row_words, nx, ny, k0, index, out);
}

using cuda::check;
using cuda::DeviceBuffer;

class CudaSlabDevice final : public SliceSlabDevice {
 public:
  CudaSlabDevice() {
    check(cudaStreamCreate(&stream_), "stream creation");
    check(cudaEventCreate(&start_), "event creation");
    check(cudaEventCreate(&kernel_start_), "event creation");
    check(cudaEventCreate(&kernel_end_), "event creation");
    check(cudaEventCreate(&end_), "event creation");
  }
  ~CudaSlabDevice() override {
    cudaEventDestroy(start_);
    cudaEventDestroy(kernel_start_);
    cudaEventDestroy(kernel_end_);
    cudaEventDestroy(end_);
    cudaStreamDestroy(stream_);
  }

  void begin(const SliceShading& shading, const SlabShape& shape, std::int64_t max_layers) override {
    std::size_t free_before = 0, free_after = 0, total = 0;
    check(cudaMemGetInfo(&free_before, &total), "query of the GPU's free memory");
    shape_ = shape;
    params_ = shading.params;
    frame_ = shading.frame;
    ramp_.allocate(shading.ramp.size(), "allocation of the ramp");
    lookup_.allocate(shading.lookup.size(), "allocation of the lookup");
    perm_.allocate(shading.perm.size(), "allocation of the noise's table");
    check(cudaMemcpy(perm_.data, shading.perm.data(), shading.perm.size(), cudaMemcpyHostToDevice),
          "copy of the noise's table");
    if (!shading.ramp.empty())
      check(cudaMemcpy(ramp_.data, shading.ramp.data(), shading.ramp.size() * sizeof(ShadeRampStop),
                       cudaMemcpyHostToDevice),
            "copy of the ramp");
    if (!shading.lookup.empty())
      check(cudaMemcpy(lookup_.data, shading.lookup.data(), shading.lookup.size() * sizeof(ShadeColour),
                       cudaMemcpyHostToDevice),
            "copy of the lookup");
    params_.ramp = ramp_.data;
    params_.lookup = lookup_.data;
    params_.perm = perm_.data;
    const auto layers = static_cast<std::size_t>(max_layers);
    bits_.allocate(layers * static_cast<std::size_t>(shape.ny * shape.row_words), "allocation of the solid's slab");
    out_.allocate(layers * static_cast<std::size_t>(shape.nx * shape.ny), "allocation of the colours' slab");
    check(cudaMemGetInfo(&free_after, &total), "query of the GPU's free memory");
    measured_ = free_before > free_after ? free_before - free_after : 0;
  }

  void colour(const std::uint64_t* bits, std::int64_t k0, std::int64_t layers, ShadeColour* out) override {
    const auto words = static_cast<std::size_t>(layers * shape_.ny * shape_.row_words);
    const std::int64_t count = layers * shape_.ny * shape_.nx;
    check(cudaEventRecord(start_, stream_), "event record");
    check(cudaMemcpyAsync(bits_.data, bits, words * sizeof(std::uint64_t), cudaMemcpyHostToDevice, stream_),
          "copy of the solid");
    check(cudaEventRecord(kernel_start_, stream_), "event record");
    const int block = 256;
    const auto blocks = static_cast<unsigned>(std::min<std::int64_t>((count + block - 1) / block, 1 << 20));
    colour_slab_kernel<<<blocks, block, 0, stream_>>>(params_, frame_, bits_.data, shape_.row_words, shape_.nx,
                                                      shape_.ny, k0, count, out_.data);
    check(cudaGetLastError(), "launch of the colouring kernel");
    check(cudaEventRecord(kernel_end_, stream_), "event record");
    check(cudaMemcpyAsync(out, out_.data, static_cast<std::size_t>(count) * sizeof(ShadeColour),
                          cudaMemcpyDeviceToHost, stream_),
          "copy of the colours");
    check(cudaEventRecord(end_, stream_), "event record");
    check(cudaStreamSynchronize(stream_), "the colouring kernel");
    float in_ms = 0, kernel_ms = 0, out_ms = 0;
    check(cudaEventElapsedTime(&in_ms, start_, kernel_start_), "event timing");
    check(cudaEventElapsedTime(&kernel_ms, kernel_start_, kernel_end_), "event timing");
    check(cudaEventElapsedTime(&out_ms, kernel_end_, end_), "event timing");
    kernel_ms_ += kernel_ms;
    copy_ms_ += in_ms + out_ms;
  }

  double kernel_ms() const override { return kernel_ms_; }
  double copy_ms() const override { return copy_ms_; }
  std::uint64_t measured_bytes() const override { return measured_; }

 private:
  cudaStream_t stream_{};
  cudaEvent_t start_{}, kernel_start_{}, kernel_end_{}, end_{};
  SlabShape shape_;
  SliceShadeParams params_;
  SliceVoxelFrame frame_;
  DeviceBuffer<ShadeRampStop> ramp_;
  DeviceBuffer<ShadeColour> lookup_;
  DeviceBuffer<std::uint8_t> perm_;
  DeviceBuffer<std::uint64_t> bits_;
  DeviceBuffer<ShadeColour> out_;
  double kernel_ms_ = 0.0, copy_ms_ = 0.0;
  std::uint64_t measured_ = 0;
};

}  // namespace

std::unique_ptr<SliceSlabDevice> make_cuda_slab_device(std::uint64_t& budget) {
  if (const std::string& why = cuda_unavailable_reason(); !why.empty()) throw Error(ErrorCode::invalid_argument, why);
  cuda::select_gpu(budget);
  return std::make_unique<CudaSlabDevice>();
}

}  // namespace voxd::detail
