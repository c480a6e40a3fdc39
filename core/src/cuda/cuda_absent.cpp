// A build without the CUDA backend (-DVOXD_CUDA=OFF, or no nvcc found):
// there are no GPUs to use, and asking for one says how to get them.
#include <memory>
#include <string>
#include <vector>

#include "voxd/compute_device.h"
#include "voxd/error.h"
#include "voxelize/coverage_device.h"
#include "voxelize/sdf_device.h"
#include "voxelize/slice_device.h"

namespace voxd {

bool cuda_built() noexcept { return false; }

const std::vector<GpuInfo>& cuda_devices() {
  static const std::vector<GpuInfo> none;
  return none;
}

const std::string& cuda_unavailable_reason() {
  static const std::string reason =
      "device cuda: this voxd was built without its CUDA backend (configure with -DVOXD_CUDA=ON where nvcc is "
      "installed); use device auto or cpu";
  return reason;
}

namespace detail {
std::unique_ptr<SliceSlabDevice> make_cuda_slab_device(std::uint64_t&) {
  throw Error(ErrorCode::invalid_argument, cuda_unavailable_reason());
}
std::unique_ptr<CoverageSlabDevice> make_cuda_coverage_device(std::uint64_t&) {
  throw Error(ErrorCode::invalid_argument, cuda_unavailable_reason());
}
}  // namespace detail

namespace sdf {
std::unique_ptr<SdfBandDevice> make_cuda_sdf_device(std::uint64_t&) {
  throw Error(ErrorCode::invalid_argument, cuda_unavailable_reason());
}
}  // namespace sdf

}  // namespace voxd
