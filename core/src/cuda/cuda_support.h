#pragma once
// What every CUDA backend file needs: CUDA calls that must succeed, device
// buffers freed with their owner, and a stream whose kernels and copies are
// timed apart. nvcc only.
#include <cuda_runtime.h>

#include <cstddef>
#include <stdexcept>
#include <string>

#include "voxd/error.h"

namespace voxd::detail::cuda {

// A CUDA call that must succeed: what failed and CUDA's words for it. Out
// of memory is the user's to act on (a smaller budget, or the CPU).
inline void check(cudaError_t status, const char* what) {
  if (status == cudaSuccess) return;
  const std::string message = std::string("CUDA ") + what + " failed: " + cudaGetErrorString(status);
  if (status == cudaErrorMemoryAllocation)
    throw Error(ErrorCode::limit_exceeded, message + " (lower the GPU memory budget, or use device cpu)");
  throw std::runtime_error(message);
}

template <class T>
struct DeviceBuffer {
  T* data = nullptr;
  std::size_t capacity = 0;
  DeviceBuffer() = default;
  DeviceBuffer(const DeviceBuffer&) = delete;
  DeviceBuffer& operator=(const DeviceBuffer&) = delete;
  ~DeviceBuffer() {
    if (data) cudaFree(data);
  }
  void allocate(std::size_t count, const char* what) {
    if (data) cudaFree(data);
    data = nullptr;
    capacity = 0;
    if (count > 0) check(cudaMalloc(reinterpret_cast<void**>(&data), count * sizeof(T)), what);
    capacity = count;
  }
  // Room for at least `count`, reallocated (contents lost) when short.
  void reserve(std::size_t count, const char* what) {
    if (count > capacity) allocate(count, what);
  }
  void upload(const T* host, std::size_t count, cudaStream_t stream, const char* what) {
    if (count > 0) check(cudaMemcpyAsync(data, host, count * sizeof(T), cudaMemcpyHostToDevice, stream), what);
  }
};

// One stream, and the milliseconds its kernels and its copies took.
class TimedStream {
 public:
  TimedStream() {
    check(cudaStreamCreate(&stream_), "stream creation");
    check(cudaEventCreate(&begin_), "event creation");
    check(cudaEventCreate(&end_), "event creation");
  }
  ~TimedStream() {
    cudaEventDestroy(begin_);
    cudaEventDestroy(end_);
    cudaStreamDestroy(stream_);
  }
  TimedStream(const TimedStream&) = delete;
  TimedStream& operator=(const TimedStream&) = delete;

  cudaStream_t get() const { return stream_; }
  // Runs `enqueue` (kernels or copies on this stream), waits for them, and
  // adds their time to the kernels' or the copies'.
  template <typename Enqueue>
  void timed(bool kernel, const char* what, const Enqueue& enqueue) {
    check(cudaEventRecord(begin_, stream_), "event record");
    enqueue();
    check(cudaGetLastError(), what);
    check(cudaEventRecord(end_, stream_), "event record");
    check(cudaStreamSynchronize(stream_), what);
    float ms = 0;
    check(cudaEventElapsedTime(&ms, begin_, end_), "event timing");
    (kernel ? kernel_ms_ : copy_ms_) += ms;
  }
  double kernel_ms() const { return kernel_ms_; }
  double copy_ms() const { return copy_ms_; }

 private:
  cudaStream_t stream_{};
  cudaEvent_t begin_{}, end_{};
  double kernel_ms_ = 0.0, copy_ms_ = 0.0;
};

// The device memory allocations have taken since construction, at most.
class MemoryWatch {
 public:
  MemoryWatch() { check(cudaMemGetInfo(&free_before_, &total_), "query of the GPU's free memory"); }
  void sample() {
    std::size_t free_now = 0, total = 0;
    check(cudaMemGetInfo(&free_now, &total), "query of the GPU's free memory");
    if (free_before_ > free_now && free_before_ - free_now > peak_) peak_ = free_before_ - free_now;
  }
  std::size_t peak() const { return peak_; }

 private:
  std::size_t free_before_ = 0, total_ = 0, peak_ = 0;
};

// Device 0 selected, and the budget: `budget`, or 0 for three quarters of
// the memory free now.
inline void select_gpu(std::uint64_t& budget) {
  check(cudaSetDevice(0), "selection of GPU 0");
  if (budget == 0) {
    std::size_t free = 0, total = 0;
    check(cudaMemGetInfo(&free, &total), "query of the GPU's free memory");
    budget = free / 4 * 3;
  }
}

}  // namespace voxd::detail::cuda
