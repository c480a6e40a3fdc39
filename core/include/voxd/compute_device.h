#pragma once
// Where the engine computes what it can compute on a GPU: the CPU, or a CUDA
// GPU when the engine was built with its CUDA backend (-DVOXD_CUDA=ON) and
// the machine has one. Results are the same bytes either way; only the time
// differs. The slice functions' colours (voxd/voxelize/slice_functions.h)
// and grey coverage (voxd/voxelize/coverage.h) run on the GPU; the solid
// the colours paint is made on the CPU, where it is at the machine's limit.
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "voxd/enum_names.h"

namespace voxd {

enum class ComputeDevice {
  automatic,  // the GPU when there is one and the work pays for it, else the CPU
  cpu,
  cuda,       // a CUDA GPU; an error where there is none
};

inline constexpr EnumNames<ComputeDevice, 3> kComputeDeviceNames{
    {{ComputeDevice::automatic, "auto"}, {ComputeDevice::cpu, "cpu"}, {ComputeDevice::cuda, "cuda"}}};
inline const char* to_string(ComputeDevice d) noexcept { return name_of(kComputeDeviceNames, d); }
inline std::optional<ComputeDevice> compute_device_from_string(std::string_view name) {
  return value_named(kComputeDeviceNames, name);
}

// What a run on a device did, for the job's record and the benchmarks.
struct DeviceRunReport {
  ComputeDevice device = ComputeDevice::cpu;  // where the work ran (cpu or cuda)
  std::int64_t slabs = 0;                     // GPU: slabs of z layers, one after another
  std::int64_t passes = 0;                    // GPU: kernel passes (a slab's rows in groups that fit, coverage)
  std::uint64_t gpu_bytes = 0;                // GPU: memory it may hold at once, as planned
  std::uint64_t gpu_measured_bytes = 0;       // GPU: the free memory its allocations took, measured
  double gpu_kernel_ms = 0.0;                 // GPU: time in kernels
  double gpu_copy_ms = 0.0;                   // GPU: time copying in and out
};

struct GpuInfo {
  std::string name;
  std::uint64_t memory_bytes = 0;
  int compute_major = 0, compute_minor = 0;
};

// Whether this build has the CUDA backend.
bool cuda_built() noexcept;

// The CUDA GPUs this process may use (CUDA_VISIBLE_DEVICES is honoured):
// empty without the backend, a driver or a GPU. Probed once per process.
const std::vector<GpuInfo>& cuda_devices();

// Why work asked for on ComputeDevice::cuda cannot run here, in words a user
// can act on; empty when it can (the backend is built and a GPU is present).
const std::string& cuda_unavailable_reason();

}  // namespace voxd
