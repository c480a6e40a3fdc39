// The signed distance field's GPU path, on a machine with or without a GPU:
// the distance template instantiated for the kernel against the CPU's (the
// same bits on slivers, degenerate and ordinary triangles), the split into
// slabs of bricks that fit a memory budget, the band made by the kernel's
// per-voxel code on its host emulation against the CPU's scatter (every
// float equal, signs and the full field included), and what device auto and
// cuda do where no GPU can be used. This executable hides every GPU from
// itself (CUDA_VISIBLE_DEVICES, set before CUDA starts), so it says the
// same on a GPU machine; tests/gpu runs the kernel itself.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "support/sdf_cases.h"
#include "support/test_checks.h"
#include "support/test_meshes.h"
#include "voxd/compute_device.h"
#include "voxd/detail/sdf_gpu.h"
#include "voxd/error.h"
#include "voxd/voxelize/sdf.h"
#include "voxelize/sdf_band_kernels.h"

namespace voxd {
namespace {

// Before main, so before anything asks CUDA for its devices.
const bool kGpusHidden = setenv("CUDA_VISIBLE_DEVICES", "", 1) == 0;

using detail::SdfBackend;
using test::code_of;

std::string first_difference(const DenseVolume<float>& a, const DenseVolume<float>& b) {
  if (a.values().size() != b.values().size()) return "sizes differ";
  for (std::size_t i = 0; i < a.values().size(); ++i)
    if (std::bit_cast<std::uint32_t>(a.values()[i]) != std::bit_cast<std::uint32_t>(b.values()[i]))
      return "voxel " + std::to_string(i) + ": " + std::to_string(a.values()[i]) + " vs " + std::to_string(b.values()[i]);
  return "none";
}

// Bit for bit, +0 and -0 told apart (a centre on the surface is +0).
bool same_bits(const DenseVolume<float>& a, const DenseVolume<float>& b) { return first_difference(a, b) == "none"; }

// ------------------------------------------------------- the distance --

// The kernel's instantiation (a plain vector of doubles) against the CPU's
// point_triangle_distance2 (glm): random triangles, slivers (a vertex a
// hair off the opposite edge), needles, two and three coincident vertices,
// points near and far.
TEST(SdfDeviceDistance, TheKernelsDistanceIsTheCpusBitForBit) {
  std::mt19937_64 rng(40);
  std::uniform_real_distribution<float> u(-2.0f, 2.0f);
  std::uniform_real_distribution<double> scale(-30.0, 3.0);
  int checked = 0;
  for (int n = 0; n < 200000; ++n) {
    float a[3], b[3], c[3];
    for (int x = 0; x < 3; ++x) a[x] = u(rng), b[x] = u(rng), c[x] = u(rng);
    switch (n % 5) {
      case 1:  // a sliver: c on the segment ab, nudged
        for (int x = 0; x < 3; ++x) c[x] = a[x] + 0.37f * (b[x] - a[x]) + (x == 1 ? 1e-6f : 0.0f);
        break;
      case 2:  // two vertices coincide
        for (int x = 0; x < 3; ++x) c[x] = a[x];
        break;
      case 3:  // a point
        for (int x = 0; x < 3; ++x) b[x] = c[x] = a[x];
        break;
      default:
        break;
    }
    const double f = std::pow(2.0, scale(rng));
    const sdf::Vec3d p(a[0] + f * u(rng), a[1] + f * u(rng), a[2] + f * u(rng));
    const double gpu = sdf::distance2(sdf::device_triangle(a, b, c), p);
    const double cpu = point_triangle_distance2({p.x, p.y, p.z}, glm::dvec3(a[0], a[1], a[2]),
                                                glm::dvec3(b[0], b[1], b[2]), glm::dvec3(c[0], c[1], c[2]));
    ASSERT_EQ(std::bit_cast<std::uint64_t>(gpu), std::bit_cast<std::uint64_t>(cpu)) << "case " << n;
    ++checked;
  }
  EXPECT_EQ(checked, 200000);
}

// ------------------------------------------------------------ the plan --

TEST(SdfDevicePlan, SlabsAreWholeBricksThatFitBesideTheScene) {
  const Grid g = test::make_grid({50, 30, 45});
  const std::uint64_t layer = detail::sdf_layer_bytes(g);
  EXPECT_EQ(layer, 50u * 30u * 4u);
  const detail::SdfSlabPlan plan = detail::plan_sdf_slabs(g, 1000, 1000 + 20 * layer);
  EXPECT_EQ(plan.layers_per_slab, 16);  // two bricks of 8 layers, not 20 layers
  EXPECT_EQ(plan.slabs, 3);
  EXPECT_EQ(plan.device_bytes, 1000 + 16 * layer);
  const detail::SdfSlabPlan whole = detail::plan_sdf_slabs(g, 1000, 1000 + 100 * layer);
  EXPECT_EQ(whole.layers_per_slab, 45);
  EXPECT_EQ(whole.slabs, 1);
  std::string message;
  EXPECT_EQ(code_of([&] { detail::plan_sdf_slabs(g, 1000, 1000 + 7 * layer); }, &message), ErrorCode::limit_exceeded);
  EXPECT_NE(message.find("cannot hold the mesh (1000 bytes with its bricks) and 8 z layers of the 50 x 30 grid"),
            std::string::npos)
      << message;
}

// -------------------------------------------------- the emulated device --

// The band by bricks equals the CPU's scatter bit for bit: three meshes (one
// open, whose sign comes from parity), odd grids, bands narrow and wide,
// model and voxel units, both sign conventions, and the full field.
TEST(SdfEmulatedDevice, EqualsTheCpuBitForBitForEveryOption) {
  const std::vector<Mesh> meshes = test::sdf_case_meshes();
  const std::int64_t sizes[] = {37, 29, 43};
  for (std::size_t m = 0; m < meshes.size(); ++m) {
    const Grid g = test::sdf_case_grid(meshes[m], sizes[m]);
    for (const SdfOptions& o : test::sdf_cases()) {
      SCOPED_TRACE(test::describe(o) + " on mesh " + std::to_string(m));
      BitVolume cpu_solid, emulated_solid;
      const DenseVolume<float> cpu = signed_distance_field(meshes[m], g, o, nullptr, &cpu_solid);
      DeviceRunReport report;
      const DenseVolume<float> emulated = detail::signed_distance_field_on(SdfBackend::host_emulation, meshes[m], g, o,
                                                                           nullptr, &emulated_solid, &report);
      EXPECT_TRUE(same_bits(emulated, cpu)) << first_difference(emulated, cpu);
      ASSERT_EQ(emulated_solid.word_count(), cpu_solid.word_count());
      EXPECT_TRUE(std::equal(cpu_solid.data(), cpu_solid.data() + cpu_solid.word_count(), emulated_solid.data()));
      EXPECT_EQ(report.slabs, 1);
    }
  }
}

// With a budget of two bricks' layers the band goes in many slabs: the same
// floats, the plan within the budget.
TEST(SdfEmulatedDevice, SlabsWithinABudgetEqualTheCpu) {
  const Mesh mesh = test::sdf_case_meshes()[0];
  const Grid g = test::sdf_case_grid(mesh, 53);
  SdfOptions o;
  o.band = 2.5;
  o.threads = 2;
  const DenseVolume<float> cpu = signed_distance_field(mesh, g, o);
  o.gpu_memory = detail::sdf_scene_bytes(mesh, g, o) + 17 * detail::sdf_layer_bytes(g);
  DeviceRunReport report;
  const DenseVolume<float> slabs =
      detail::signed_distance_field_on(SdfBackend::host_emulation, mesh, g, o, nullptr, nullptr, &report);
  EXPECT_TRUE(same_bits(slabs, cpu)) << first_difference(slabs, cpu);
  EXPECT_EQ(report.slabs, (g.dims.z + 15) / 16);
  EXPECT_GT(report.slabs, 2);
  EXPECT_LE(report.gpu_bytes, o.gpu_memory);
}

TEST(SdfEmulatedDevice, ReportsProgressHonoursCancellationAndRefusesATinyBudget) {
  const Mesh mesh = test::sdf_case_meshes()[1];
  const Grid g = test::sdf_case_grid(mesh, 30);
  SdfOptions o;
  JobControl control;
  detail::signed_distance_field_on(SdfBackend::host_emulation, mesh, g, o, &control);
  EXPECT_DOUBLE_EQ(control.progress(), 1.0);
  JobControl cancelled;
  cancelled.request_cancel();
  EXPECT_EQ(code_of([&] { detail::signed_distance_field_on(SdfBackend::host_emulation, mesh, g, o, &cancelled); }),
            ErrorCode::cancelled);
  o.gpu_memory = 1000;
  std::string message;
  EXPECT_EQ(code_of([&] { detail::signed_distance_field_on(SdfBackend::host_emulation, mesh, g, o); }, &message),
            ErrorCode::limit_exceeded);
  EXPECT_NE(message.find("raise the budget or use device cpu"), std::string::npos) << message;
}

// ------------------------------------------------------- without a GPU --

TEST(SdfWithoutGpu, AutoRunsOnTheCpuAndCudaIsRefusedSayingWhy) {
  ASSERT_TRUE(kGpusHidden);
  const Mesh mesh = test::sdf_case_meshes()[0];
  const Grid big = test::sdf_case_grid(mesh, 170);  // past the 2^21 voxels where auto would take a GPU
  ASSERT_GE(big.voxel_count(), std::uint64_t{1} << 21);
  SdfOptions o;
  o.band = 1.5;
  o.device = ComputeDevice::automatic;
  EXPECT_EQ(sdf_device_for(o, big), ComputeDevice::cpu);
  DeviceRunReport report;
  report.device = ComputeDevice::cuda;
  const DenseVolume<float> automatic = signed_distance_field(mesh, big, o, nullptr, nullptr, &report);
  EXPECT_EQ(report.device, ComputeDevice::cpu);
  o.device = ComputeDevice::cpu;
  EXPECT_TRUE(same_bits(signed_distance_field(mesh, big, o), automatic));

  o.device = ComputeDevice::cuda;
  EXPECT_EQ(sdf_device_for(o, big), ComputeDevice::cuda);
  std::string message;
  EXPECT_EQ(code_of([&] { signed_distance_field(mesh, test::sdf_case_grid(mesh, 20), o); }, &message),
            ErrorCode::invalid_argument);
  EXPECT_EQ(message, cuda_unavailable_reason());
  ASSERT_TRUE(sdf_slabs_refusal(o).has_value());
  EXPECT_NE(sdf_slabs_refusal(o)->find("device cuda computes the band of the whole grid at once"), std::string::npos);
}

}  // namespace
}  // namespace voxd
