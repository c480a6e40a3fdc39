// Grey coverage on a CUDA GPU (ctest label gpu: run where a GPU is, by
// scripts/test.sh when nvidia-smi finds one and by bench/gpu/check.sh): the
// kernels' floats are the CPU's, bit for bit, for every sampling on four
// meshes (one open) and odd grids, whole, slab by slab and streamed; device
// auto takes the GPU where it pays and leaves to the CPU what it cannot
// hold; what the GPU held fits the budget it was given, and the memory its
// allocations took, measured, is what the plan estimated.
#include <cstdint>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "support/coverage_cases.h"
#include "support/slice_cases.h"
#include "support/test_meshes.h"
#include "voxd/compute_device.h"
#include "voxd/detail/coverage_gpu.h"
#include "voxd/error.h"
#include "voxd/voxelize/coverage.h"

namespace voxd {
namespace {

class CoverageCuda : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(cuda_unavailable_reason().empty()) << "the gpu tests need a CUDA GPU: " << cuda_unavailable_reason();
  }
};

TEST_F(CoverageCuda, EverySamplingEqualsTheCpuOnFourMeshesAndOddGrids) {
  const std::vector<Mesh> ms = test::coverage_case_meshes();
  const std::int64_t sizes[] = {61, 127, 203, 99};
  for (std::size_t m = 0; m < ms.size(); ++m) {
    const Grid g = test::slice_case_grid(ms[m], sizes[m]);
    for (CoverageOptions o : test::coverage_cases()) {
      SCOPED_TRACE(std::string(to_string(o.sampling)) + " k=" + std::to_string(o.rays) + " on mesh " +
                   std::to_string(m));
      o.device = ComputeDevice::cpu;
      const DenseVolume<float> cpu = voxelize_coverage(ms[m], g, o);
      o.device = ComputeDevice::cuda;
      CoverageRunReport report;
      const DenseVolume<float> gpu = voxelize_coverage(ms[m], g, o, nullptr, &report);
      EXPECT_EQ(report.device, ComputeDevice::cuda);
      EXPECT_EQ(report.slabs, 1);
      EXPECT_GT(report.gpu_kernel_ms, 0.0);
      EXPECT_TRUE(gpu.values() == cpu.values());
    }
  }
}

TEST_F(CoverageCuda, SlabsAndGroupsWithinABudgetEqualTheCpuAndTheMeasuredMemory) {
  const Mesh mesh = test::coverage_case_meshes()[0];
  const Grid g = test::slice_case_grid(mesh, 151);
  CoverageOptions o;
  const DenseVolume<float> cpu = voxelize_coverage(mesh, g, o);
  o.device = ComputeDevice::cuda;
  o.gpu_memory = detail::coverage_scene_bytes(mesh, g) + 8 + 14 * detail::coverage_layer_bytes(g);
  CoverageRunReport report;
  const DenseVolume<float> gpu = voxelize_coverage(mesh, g, o, nullptr, &report);
  EXPECT_GE(report.slabs, 10);
  EXPECT_GT(report.passes, report.slabs);
  EXPECT_LE(report.gpu_bytes, o.gpu_memory);
  // The estimate against what the allocations took: the driver rounds each
  // of the 9 up to its 2 MiB pages.
  EXPECT_GT(report.gpu_measured_bytes, 0u);
  EXPECT_LE(report.gpu_measured_bytes, report.gpu_bytes + 9 * (std::uint64_t{2} << 20));
  EXPECT_TRUE(gpu.values() == cpu.values());

  std::vector<float> streamed;
  voxelize_coverage_streamed(mesh, g, o, 9, [&](std::int64_t k0, const DenseVolume<float>& slab) {
    EXPECT_EQ(static_cast<std::size_t>(k0) * slab.slab_size(), streamed.size());
    streamed.insert(streamed.end(), slab.values().begin(), slab.values().end());
  });
  EXPECT_TRUE(streamed == std::vector<float>(cpu.values().begin(), cpu.values().end()));
}

TEST_F(CoverageCuda, AutoTakesTheGpuForLargeGridsAndLeavesToTheCpuWhatItCannotHold) {
  const Mesh mesh = test::coverage_case_meshes()[1];
  CoverageOptions o;
  o.device = ComputeDevice::automatic;
  EXPECT_EQ(coverage_device_for(o, test::slice_case_grid(mesh, 40)), ComputeDevice::cpu);
  const Grid big = test::slice_case_grid(mesh, 200);
  EXPECT_EQ(coverage_device_for(o, big), ComputeDevice::cuda);
  CoverageRunReport report;
  const DenseVolume<float> automatic = voxelize_coverage(mesh, big, o, nullptr, &report);
  EXPECT_EQ(report.device, ComputeDevice::cuda);
  o.device = ComputeDevice::cpu;
  const DenseVolume<float> cpu = voxelize_coverage(mesh, big, o);
  EXPECT_TRUE(automatic.values() == cpu.values());
  o.device = ComputeDevice::automatic;
  o.gpu_memory = 1000;
  EXPECT_TRUE(voxelize_coverage(mesh, big, o, nullptr, &report).values() == cpu.values());
  EXPECT_EQ(report.device, ComputeDevice::cpu);
  o.device = ComputeDevice::cuda;
  try {
    voxelize_coverage(mesh, big, o);
    ADD_FAILURE() << "ran in 1000 bytes";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::limit_exceeded);
    EXPECT_NE(std::string(e.what()).find("cannot hold the mesh"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace voxd
