// The CUDA GPUs this process sees (voxd/compute_device.h), in a build with
// the CUDA backend.
#include <cuda_runtime.h>

#include <string>
#include <vector>

#include "voxd/compute_device.h"

namespace voxd {
namespace {

struct Probe {
  std::vector<GpuInfo> devices;
  std::string reason;
};

const Probe& probe() {
  static const Probe result = [] {
    Probe p;
    int count = 0;
    const cudaError_t status = cudaGetDeviceCount(&count);
    if (status != cudaSuccess) {
      // No driver, no device, or CUDA_VISIBLE_DEVICES hiding them all.
      const char* what = status == cudaErrorInsufficientDriver
                             ? "no NVIDIA driver, or one older than this build's CUDA runtime"
                         : status == cudaErrorNoDevice ? "no GPU visible (CUDA_VISIBLE_DEVICES may hide them)"
                                                       : "CUDA could not start";
      p.reason = std::string("device cuda: no usable CUDA GPU on this machine (") + what + ": " +
                 cudaGetErrorString(status) + "); use device auto or cpu";
      return p;
    }
    for (int i = 0; i < count; ++i) {
      cudaDeviceProp prop{};
      if (cudaGetDeviceProperties(&prop, i) != cudaSuccess) continue;
      p.devices.push_back({prop.name, static_cast<std::uint64_t>(prop.totalGlobalMem), prop.major, prop.minor});
    }
    if (p.devices.empty()) p.reason = "device cuda: no CUDA GPU on this machine; use device auto or cpu";
    return p;
  }();
  return result;
}

}  // namespace

bool cuda_built() noexcept { return true; }
const std::vector<GpuInfo>& cuda_devices() { return probe().devices; }
const std::string& cuda_unavailable_reason() { return probe().reason; }

}  // namespace voxd
