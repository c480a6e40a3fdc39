// The slice functions on a CUDA GPU (ctest label gpu: run where a GPU is,
// by scripts/test.sh when nvidia-smi finds one and by bench/gpu/check.sh):
// the kernel's colours are the CPU's, byte for byte, for every function on
// three meshes and odd grids, whole or slab by slab; device auto takes the
// GPU where it pays; what the GPU held fits the budget it was given, and
// the memory its allocations took, measured, is what the plan estimated.
#include <cstdint>
#include <string>

#include <gtest/gtest.h>

#include "support/slice_cases.h"
#include "support/test_meshes.h"
#include "voxd/compute_device.h"
#include "voxd/detail/slice_gpu.h"
#include "voxd/error.h"
#include "voxd/transform.h"
#include "voxd/voxelize/slice_functions.h"

namespace voxd {
namespace {

Grid grid_for(const Mesh& mesh, std::int64_t n) { return test::slice_case_grid(mesh, n); }
std::vector<Mesh> meshes() { return test::slice_case_meshes(); }

class SliceCuda : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(cuda_unavailable_reason().empty()) << "the gpu tests need a CUDA GPU: " << cuda_unavailable_reason();
  }
};

TEST_F(SliceCuda, EveryFunctionEqualsTheCpuOnThreeMeshesAndOddGrids) {
  const std::vector<Mesh> ms = meshes();
  const std::int64_t sizes[] = {61, 127, 203};
  for (std::size_t m = 0; m < ms.size(); ++m) {
    const Grid g = grid_for(ms[m], sizes[m]);
    for (const SliceFunction f : test::kAllSliceFunctions) {
      SCOPED_TRACE(std::string(to_string(f)) + " on mesh " + std::to_string(m));
      SliceOptions o = test::slice_case(f);
      o.device = ComputeDevice::cpu;
      const DenseVolume<Rgba8> cpu = voxelize_slice(ms[m], g, o);
      o.device = ComputeDevice::cuda;
      SliceRunReport report;
      const DenseVolume<Rgba8> gpu = voxelize_slice(ms[m], g, o, nullptr, &report);
      EXPECT_EQ(report.device, ComputeDevice::cuda);
      EXPECT_EQ(report.slabs, 1);
      EXPECT_TRUE(gpu.values() == cpu.values());
    }
  }
}

TEST_F(SliceCuda, SlabBySlabEqualsTheCpuAndHoldsNoMoreThanTheBudget) {
  const std::vector<Mesh> ms = meshes();
  const Grid g = grid_for(ms[0], 151);
  for (const SliceFunction f : {SliceFunction::marble, SliceFunction::custom, SliceFunction::color_ramp}) {
    SCOPED_TRACE(to_string(f));
    SliceOptions o = test::slice_case(f);
    const DenseVolume<Rgba8> cpu = voxelize_slice(ms[0], g, o);
    o.device = ComputeDevice::cuda;
    o.gpu_memory = 4096 + 7 * detail::slice_layer_bytes(g);
    SliceRunReport report;
    const DenseVolume<Rgba8> gpu = voxelize_slice(ms[0], g, o, nullptr, &report);
    EXPECT_GE(report.slabs, 20);
    EXPECT_LE(report.gpu_bytes, o.gpu_memory);
    // The estimate against what the allocations took: the driver rounds
    // each of the 6 up to its 2 MiB pages.
    EXPECT_GT(report.gpu_measured_bytes, 0u);
    EXPECT_LE(report.gpu_measured_bytes, report.gpu_bytes + 6 * (std::uint64_t{2} << 20));
    EXPECT_TRUE(gpu.values() == cpu.values());
  }
}

TEST_F(SliceCuda, NoiseOptionsAtTheirLimitsEqualTheCpu) {
  const Mesh mesh = meshes()[1];
  const Grid g = grid_for(mesh, 99);
  for (const int octaves : {1, 16})
    for (const SliceFunction f : {SliceFunction::wood, SliceFunction::marble, SliceFunction::rock}) {
      SCOPED_TRACE(std::string(to_string(f)) + " octaves " + std::to_string(octaves));
      SliceOptions o = test::slice_case(f);
      o.octaves = octaves;
      o.seed = 0xfedcba9876543210ull;
      o.noise_scale = 0.013;
      o.turbulence = 3.5;
      o.noise_colors = {{0, 0, 0, 1}, {255, 255, 255, 255}};
      const DenseVolume<Rgba8> cpu = voxelize_slice(mesh, g, o);
      o.device = ComputeDevice::cuda;
      EXPECT_TRUE(voxelize_slice(mesh, g, o).values() == cpu.values());
    }
}

TEST_F(SliceCuda, AutoTakesTheGpuForNoiseOnLargeGrids) {
  const Mesh mesh = meshes()[0];
  SliceOptions o = test::slice_case(SliceFunction::rock);
  o.device = ComputeDevice::automatic;
  EXPECT_EQ(slice_device_for(o, grid_for(mesh, 40)), ComputeDevice::cpu);
  const Grid big = grid_for(mesh, 200);
  EXPECT_EQ(slice_device_for(o, big), ComputeDevice::cuda);
  SliceRunReport report;
  const DenseVolume<Rgba8> automatic = voxelize_slice(mesh, big, o, nullptr, &report);
  EXPECT_EQ(report.device, ComputeDevice::cuda);
  EXPECT_GT(report.gpu_kernel_ms, 0.0);
  o.device = ComputeDevice::cpu;
  EXPECT_TRUE(voxelize_slice(mesh, big, o).values() == automatic.values());
  o.function = SliceFunction::single_color;
  o.device = ComputeDevice::automatic;
  EXPECT_EQ(slice_device_for(o, big), ComputeDevice::cpu);
}

TEST_F(SliceCuda, AutoLeavesToTheCpuWhatTheGpuCannotHold) {
  const Mesh mesh = meshes()[0];
  const Grid big = grid_for(mesh, 200);
  SliceOptions o = test::slice_case(SliceFunction::marble);
  const DenseVolume<Rgba8> cpu = voxelize_slice(mesh, big, o);
  o.device = ComputeDevice::automatic;
  o.gpu_memory = 1000;
  SliceRunReport report;
  report.device = ComputeDevice::cuda;
  EXPECT_TRUE(voxelize_slice(mesh, big, o, nullptr, &report).values() == cpu.values());
  EXPECT_EQ(report.device, ComputeDevice::cpu);
}

TEST_F(SliceCuda, ABudgetBelowOneLayerIsRefused) {
  const Mesh mesh = meshes()[0];
  SliceOptions o = test::slice_case(SliceFunction::wood);
  o.device = ComputeDevice::cuda;
  o.gpu_memory = 1000;
  try {
    voxelize_slice(mesh, grid_for(mesh, 64), o);
    ADD_FAILURE() << "ran in 1000 bytes";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::limit_exceeded);
    EXPECT_NE(std::string(e.what()).find("cannot hold one z layer"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace voxd
