// The signed distance field's band on a CUDA GPU (ctest label gpu: run where
// a GPU is, by scripts/test.sh when nvidia-smi finds one and by
// bench/gpu/check.sh): the kernel's floats are the CPU's, bit for bit, for
// every option on three meshes (one open) and odd grids, whole and slab by
// slab; device auto takes the GPU where it pays and leaves to the CPU what
// it cannot hold; what the GPU held fits the budget, and the memory its
// allocations took, measured, is what the plan estimated.
#include <algorithm>
#include <bit>
#include <cstdint>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "support/sdf_cases.h"
#include "support/test_meshes.h"
#include "voxd/compute_device.h"
#include "voxd/detail/sdf_gpu.h"
#include "voxd/error.h"
#include "voxd/voxelize/sdf.h"

namespace voxd {
namespace {

bool same_bits(const DenseVolume<float>& a, const DenseVolume<float>& b) {
  return a.values().size() == b.values().size() &&
         std::equal(a.values().begin(), a.values().end(), b.values().begin(),
                    [](float x, float y) { return std::bit_cast<std::uint32_t>(x) == std::bit_cast<std::uint32_t>(y); });
}

class SdfCuda : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(cuda_unavailable_reason().empty()) << "the gpu tests need a CUDA GPU: " << cuda_unavailable_reason();
  }
};

TEST_F(SdfCuda, EveryOptionEqualsTheCpuOnThreeMeshesAndOddGrids) {
  const std::vector<Mesh> meshes = test::sdf_case_meshes();
  const std::int64_t sizes[] = {61, 127, 203};
  for (std::size_t m = 0; m < meshes.size(); ++m) {
    const Grid g = test::sdf_case_grid(meshes[m], sizes[m]);
    for (SdfOptions o : test::sdf_cases()) {
      SCOPED_TRACE(test::describe(o) + " on mesh " + std::to_string(m));
      o.device = ComputeDevice::cpu;
      const DenseVolume<float> cpu = signed_distance_field(meshes[m], g, o);
      o.device = ComputeDevice::cuda;
      DeviceRunReport report;
      const DenseVolume<float> gpu = signed_distance_field(meshes[m], g, o, nullptr, nullptr, &report);
      EXPECT_EQ(report.device, ComputeDevice::cuda);
      EXPECT_EQ(report.slabs, 1);
      EXPECT_GT(report.gpu_kernel_ms, 0.0);
      EXPECT_TRUE(same_bits(gpu, cpu));
    }
  }
}

TEST_F(SdfCuda, SlabBySlabEqualsTheCpuAndHoldsWhatWasPlanned) {
  const Mesh mesh = test::sdf_case_meshes()[0];
  const Grid g = test::sdf_case_grid(mesh, 151);
  SdfOptions o;
  const DenseVolume<float> cpu = signed_distance_field(mesh, g, o);
  o.device = ComputeDevice::cuda;
  o.gpu_memory = detail::sdf_scene_bytes(mesh, g, o) + 20 * detail::sdf_layer_bytes(g);
  DeviceRunReport report;
  const DenseVolume<float> gpu = signed_distance_field(mesh, g, o, nullptr, nullptr, &report);
  EXPECT_GE(report.slabs, 3);
  EXPECT_LE(report.gpu_bytes, o.gpu_memory);
  // The estimate against what the allocations took: the driver rounds each
  // of the 6 up to its 2 MiB pages.
  EXPECT_GT(report.gpu_measured_bytes, 0u);
  EXPECT_LE(report.gpu_measured_bytes, report.gpu_bytes + 6 * (std::uint64_t{2} << 20));
  EXPECT_TRUE(same_bits(gpu, cpu));
}

TEST_F(SdfCuda, AutoTakesTheGpuForLargeGridsAndLeavesToTheCpuWhatItCannotHold) {
  const Mesh mesh = test::sdf_case_meshes()[2];
  SdfOptions o;
  o.device = ComputeDevice::automatic;
  EXPECT_EQ(sdf_device_for(o, test::sdf_case_grid(mesh, 40)), ComputeDevice::cpu);
  const Grid big = test::sdf_case_grid(mesh, 200);
  EXPECT_EQ(sdf_device_for(o, big), ComputeDevice::cuda);
  DeviceRunReport report;
  const DenseVolume<float> automatic = signed_distance_field(mesh, big, o, nullptr, nullptr, &report);
  EXPECT_EQ(report.device, ComputeDevice::cuda);
  o.device = ComputeDevice::cpu;
  const DenseVolume<float> cpu = signed_distance_field(mesh, big, o);
  EXPECT_TRUE(same_bits(automatic, cpu));
  o.device = ComputeDevice::automatic;
  o.gpu_memory = 1000;
  EXPECT_TRUE(same_bits(signed_distance_field(mesh, big, o, nullptr, nullptr, &report), cpu));
  EXPECT_EQ(report.device, ComputeDevice::cpu);
}

}  // namespace
}  // namespace voxd
