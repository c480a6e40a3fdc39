// The slice functions' GPU path, on a machine with or without a GPU: the
// sine and cosine both sides share against a long-double reference, the
// split into slabs that fit a memory budget, the slab loop run on the host
// emulation of the kernel (the same shading code) against the CPU path, and
// what device auto and cuda do where no GPU can be used. This executable
// hides every GPU from itself (CUDA_VISIBLE_DEVICES, set before CUDA starts),
// so it says the same on a GPU machine; tests/gpu runs the kernel itself.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <string>

#include <gtest/gtest.h>

#include "support/slice_cases.h"
#include "support/test_checks.h"
#include "support/test_meshes.h"
#include "voxd/compute_device.h"
#include "voxd/detail/slice_gpu.h"
#include "voxd/error.h"
#include "voxd/transform.h"
#include "voxd/voxelize/slice_functions.h"
#include "voxelize/slice_shading.h"

namespace voxd {
namespace {

// Before main, so before anything asks CUDA for its devices.
const bool kGpusHidden = setenv("CUDA_VISIBLE_DEVICES", "", 1) == 0;

using test::code_of;

Grid grid_for(const Mesh& mesh, std::int64_t n) { return test::slice_case_grid(mesh, n); }
Mesh turned_torus() { return test::slice_case_meshes()[0]; }

// Distance in units in the last place of the double nearest to `reference`.
double ulps(double value, long double reference) {
  const double r = static_cast<double>(reference);
  const double ulp = std::nextafter(std::abs(r), std::numeric_limits<double>::infinity()) - std::abs(r);
  return static_cast<double>(std::abs(static_cast<long double>(value) - reference) / ulp);
}

// ------------------------------------------------------------- sin, cos --

TEST(SliceTrig, SinAndCosOfTurnsAreWithinTwoUlpOfALongDoubleReference) {
  const long double two_pi = 6.283185307179586476925286766559L;
  double worst_sin = 0, worst_cos = 0;
  std::uint64_t state = 12345;
  for (int n = 0; n < 400000; ++n) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    const double unit = static_cast<double>(state >> 11) / 9007199254740992.0;
    // From tiny to thousands of turns, either sign.
    const double x = (n % 2 ? -1.0 : 1.0) * unit * std::pow(10.0, (n % 9) - 5);
    // The reference in long double: x less its nearest quarter turn
    // (exact), then the C library's sinl and cosl of at most an eighth of a
    // turn, so its argument carries no rounding that would swamp a small
    // value near a zero.
    const long double t = std::fmod(static_cast<long double>(x), 1.0L);
    const long double k = std::nearbyint(4.0L * t);
    const long double theta = two_pi * (t - k / 4.0L);
    const int quadrant = static_cast<int>(static_cast<long long>(k) & 3);
    const long double sin_theta = std::sin(theta), cos_theta = std::cos(theta);
    const long double quarter_sin[4] = {sin_theta, cos_theta, -sin_theta, -cos_theta};
    const long double quarter_cos[4] = {cos_theta, -sin_theta, -cos_theta, sin_theta};
    const long double s = quarter_sin[quadrant], c = quarter_cos[quadrant];
    // Exact zeros (x a multiple of a half turn) have no relative error to
    // measure; they are checked exactly below.
    if (std::abs(s) > 1e-9L) worst_sin = std::max(worst_sin, ulps(detail::sin_turns(x), s));
    if (std::abs(c) > 1e-9L) worst_cos = std::max(worst_cos, ulps(detail::cos_turns(x), c));
  }
  EXPECT_LE(worst_sin, 2.0);
  EXPECT_LE(worst_cos, 2.0);
}

TEST(SliceTrig, QuarterTurnsAreExactAndNonFiniteGivesZero) {
  EXPECT_EQ(detail::sin_turns(0.25), 1.0);
  EXPECT_EQ(detail::sin_turns(-0.25), -1.0);
  EXPECT_EQ(detail::sin_turns(0.5), 0.0);
  EXPECT_EQ(detail::sin_turns(1e6 + 0.75), -1.0);
  EXPECT_EQ(detail::cos_turns(0.0), 1.0);
  EXPECT_EQ(detail::cos_turns(0.5), -1.0);
  EXPECT_EQ(detail::cos_turns(0.25), 0.0);
  EXPECT_EQ(detail::cos_turns(-3.0), 1.0);
  EXPECT_EQ(detail::sin_turns(std::numeric_limits<double>::infinity()), 0.0);
  EXPECT_EQ(detail::cos_turns(std::numeric_limits<double>::quiet_NaN()), 0.0);
}

// ------------------------------------------------------------- the plan --

TEST(SliceSlabPlan, SlabsAreTheDeepestThatFitTheBudget) {
  Grid g;
  g.dims = {130, 29, 23};
  // Per layer: 29 rows of 3 words (8 bytes) and 130 * 29 colours (4 bytes).
  const std::uint64_t layer = 29 * 3 * 8 + 130 * 29 * 4;
  ASSERT_EQ(detail::slice_layer_bytes(g), layer);

  detail::SliceSlabPlan p = detail::plan_slice_slabs(g, 1000, 1000 + 5 * layer + layer - 1);
  EXPECT_EQ(p.layers_per_slab, 5);
  EXPECT_EQ(p.slabs, 5);  // 5 + 5 + 5 + 5 + 3
  EXPECT_EQ(p.device_bytes, 1000 + 5 * layer);

  p = detail::plan_slice_slabs(g, 1000, std::uint64_t{1} << 40);
  EXPECT_EQ(p.layers_per_slab, 23);
  EXPECT_EQ(p.slabs, 1);
  EXPECT_EQ(p.device_bytes, 1000 + 23 * layer);

  p = detail::plan_slice_slabs(g, 0, layer);
  EXPECT_EQ(p.layers_per_slab, 1);
  EXPECT_EQ(p.slabs, 23);

  for (const std::uint64_t budget : {std::uint64_t{999}, 1000 + layer - 1}) {
    try {
      detail::plan_slice_slabs(g, 1000, budget);
      ADD_FAILURE() << "a budget of " << budget << " bytes was planned";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::limit_exceeded);
      EXPECT_NE(std::string(e.what()).find("cannot hold one z layer of the 130 x 29 grid (" +
                                           std::to_string(layer + 1000) + " bytes"),
                std::string::npos)
          << e.what();
    }
  }
  g.dims = {0, 4, 4};
  EXPECT_EQ(detail::plan_slice_slabs(g, 1000, 10).slabs, 0);
}

// ------------------------------------------------- the emulated kernel --

// Slab by slab through the kernel's own loop, with a budget of a few
// layers, the colours are the CPU path's, byte for byte: every function,
// three meshes, odd grids.
TEST(SliceEmulatedDevice, SlabBySlabEqualsTheCpuForEveryFunction) {
  const std::vector<Mesh> meshes = test::slice_case_meshes();
  const std::int64_t sizes[] = {37, 53, 71};
  for (int m = 0; m < 3; ++m) {
    const Grid g = grid_for(meshes[m], sizes[m]);
    for (const SliceFunction f : test::kAllSliceFunctions) {
      SCOPED_TRACE(std::string(to_string(f)) + " on mesh " + std::to_string(m));
      SliceOptions o = test::slice_case(f);
      o.threads = 2;
      const DenseVolume<Rgba8> cpu = voxelize_slice(meshes[m], g, o);
      // Room for the tables (under 4 KiB) and 4 layers.
      o.gpu_memory = 4096 + 4 * detail::slice_layer_bytes(g);
      SliceRunReport report;
      const DenseVolume<Rgba8> slabs =
          detail::voxelize_slice_on(detail::SliceBackend::host_emulation, meshes[m], g, o, nullptr, &report);
      EXPECT_GT(report.slabs, 3);
      EXPECT_LE(report.gpu_bytes, o.gpu_memory);
      EXPECT_TRUE(slabs.values() == cpu.values());
    }
  }
}

TEST(SliceEmulatedDevice, ReportsProgressAndHonoursCancellation) {
  const Mesh mesh = turned_torus();
  const Grid g = grid_for(mesh, 40);
  SliceOptions o = test::slice_case(SliceFunction::marble);
  o.gpu_memory = 4096 + 3 * detail::slice_layer_bytes(g);
  JobControl control;
  detail::voxelize_slice_on(detail::SliceBackend::host_emulation, mesh, g, o, &control);
  EXPECT_DOUBLE_EQ(control.progress(), 1.0);
  JobControl cancelled;
  cancelled.request_cancel();
  EXPECT_EQ(code_of([&] { detail::voxelize_slice_on(detail::SliceBackend::host_emulation, mesh, g, o, &cancelled); }),
            ErrorCode::cancelled);
}

// A budget given that cannot hold one layer is refused before the solid is
// made: no progress, no work.
TEST(SliceEmulatedDevice, ABudgetBelowOneLayerIsRefusedBeforeAnyWork) {
  const Mesh mesh = turned_torus();
  const Grid g = grid_for(mesh, 40);
  SliceOptions o = test::slice_case(SliceFunction::rock);
  o.gpu_memory = detail::slice_layer_bytes(g);  // the layer, but not the tables beside it
  JobControl control;
  std::string message;
  EXPECT_EQ(code_of([&] { detail::voxelize_slice_on(detail::SliceBackend::host_emulation, mesh, g, o, &control); },
                    &message),
            ErrorCode::limit_exceeded);
  EXPECT_NE(message.find("cannot hold one z layer"), std::string::npos) << message;
  EXPECT_EQ(control.progress(), 0.0);
}

// ------------------------------------------------------- without a GPU --

TEST(SliceWithoutGpu, AutoRunsOnTheCpuWithTheSameBytes) {
  ASSERT_TRUE(kGpusHidden);
  EXPECT_TRUE(cuda_devices().empty());
  const Mesh mesh = turned_torus();
  const Grid big = grid_for(mesh, 160);  // past the 2^21 voxels where auto would take a GPU
  ASSERT_GE(big.voxel_count(), std::uint64_t{1} << 21);
  SliceOptions o = test::slice_case(SliceFunction::marble);
  o.device = ComputeDevice::automatic;
  EXPECT_EQ(slice_device_for(o, big), ComputeDevice::cpu);
  SliceRunReport report;
  report.device = ComputeDevice::cuda;
  const DenseVolume<Rgba8> automatic = voxelize_slice(mesh, big, o, nullptr, &report);
  EXPECT_EQ(report.device, ComputeDevice::cpu);
  o.device = ComputeDevice::cpu;
  EXPECT_TRUE(voxelize_slice(mesh, big, o).values() == automatic.values());
}

TEST(SliceWithoutGpu, CudaIsRefusedSayingWhyAndWhatToUse) {
  ASSERT_TRUE(kGpusHidden);
  const std::string& why = cuda_unavailable_reason();
  if (cuda_built())
    EXPECT_NE(why.find("device cuda: no usable CUDA GPU on this machine ("), std::string::npos) << why;
  else
    EXPECT_NE(why.find("device cuda: this voxd was built without its CUDA backend"), std::string::npos) << why;
  EXPECT_NE(why.find("use device auto or cpu"), std::string::npos) << why;

  const Mesh mesh = turned_torus();
  SliceOptions o = test::slice_case(SliceFunction::wood);
  o.device = ComputeDevice::cuda;
  EXPECT_EQ(slice_device_for(o, grid_for(mesh, 8)), ComputeDevice::cuda);
  try {
    voxelize_slice(mesh, grid_for(mesh, 20), o);
    ADD_FAILURE() << "device cuda ran without a GPU";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::invalid_argument);
    EXPECT_EQ(std::string(e.what()), why);
  }
}

TEST(SliceDevices, NamesRoundTrip) {
  for (const ComputeDevice d : {ComputeDevice::automatic, ComputeDevice::cpu, ComputeDevice::cuda})
    EXPECT_EQ(compute_device_from_string(to_string(d)), d);
  EXPECT_STREQ(to_string(ComputeDevice::automatic), "auto");
  EXPECT_FALSE(compute_device_from_string("gpu").has_value());
}

}  // namespace
}  // namespace voxd
