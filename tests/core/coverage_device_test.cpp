// Grey coverage's GPU path, on a machine with or without a GPU: the one
// conversion its arithmetic spells out (__int128 to double) against the
// compiler's, the split into slabs and groups of rows that fit a memory
// budget, the kernels' passes run on their host emulation (the same
// per-thread code: crossings in any order, sorted per column, integrated)
// against the CPU path's floats, and what device auto and cuda do where no
// GPU can be used. This executable hides every GPU from itself
// (CUDA_VISIBLE_DEVICES, set before CUDA starts), so it says the same on a
// GPU machine; tests/gpu runs the kernels themselves.
#include <cstdint>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "support/coverage_cases.h"
#include "support/slice_cases.h"
#include "support/test_checks.h"
#include "support/test_meshes.h"
#include "voxd/compute_device.h"
#include "voxd/detail/coverage_gpu.h"
#include "voxd/error.h"
#include "voxd/voxelize/coverage.h"
#include "voxelize/ray_triangle.h"

namespace voxd {
namespace {

// Before main, so before anything asks CUDA for its devices.
const bool kGpusHidden = setenv("CUDA_VISIBLE_DEVICES", "", 1) == 0;

using detail::CoverageBackend;
using test::code_of;

std::string describe(const CoverageOptions& o) {
  return std::string(to_string(o.sampling)) + " k=" + std::to_string(o.rays);
}

// Where two volumes first differ, for the failure message.
std::string first_difference(const DenseVolume<float>& a, const DenseVolume<float>& b) {
  if (a.values().size() != b.values().size()) return "sizes differ";
  for (std::size_t i = 0; i < a.values().size(); ++i)
    if (a.values()[i] != b.values()[i])
      return "voxel " + std::to_string(i) + ": " + std::to_string(a.values()[i]) + " vs " + std::to_string(b.values()[i]);
  return "none";
}

// -------------------------------------------------------- int128 to double --

// The conversion the GPU cannot be trusted to round as the CPU does,
// against GCC's own: random magnitudes of every length, either sign, and
// values built to sit exactly halfway between two doubles (ties to even).
TEST(CoverageArithmetic, Int128ToDoubleRoundsAsTheCompilerDoes) {
  std::mt19937_64 rng(2026);
  int checked = 0;
  for (int bits = 1; bits <= 126; ++bits)
    for (int n = 0; n < 400; ++n) {
      const unsigned __int128 r = (static_cast<unsigned __int128>(rng()) << 64) | rng();
      __int128 v = static_cast<__int128>(r >> (128 - bits));
      if (n % 2) v = -v;
      ASSERT_EQ(detail::int128_to_double(v), static_cast<double>(v)) << "bits " << bits << " case " << n;
      ++checked;
    }
  for (int shift = 1; shift <= 70; ++shift)
    for (std::uint64_t m : {std::uint64_t{1} << 52, (std::uint64_t{1} << 53) - 1, (std::uint64_t{1} << 52) + 1}) {
      // m * 2^shift plus exactly half of 2^shift: a tie, broken to even.
      const __int128 base = static_cast<__int128>(m) << shift;
      for (const __int128 v : {base + (static_cast<__int128>(1) << (shift - 1)), base - 1, base + 1}) {
        ASSERT_EQ(detail::int128_to_double(v), static_cast<double>(v)) << "shift " << shift;
        ASSERT_EQ(detail::int128_to_double(-v), static_cast<double>(-v)) << "shift " << shift;
        checked += 2;
      }
    }
  const __int128 lowest = static_cast<__int128>(static_cast<unsigned __int128>(1) << 127);
  EXPECT_EQ(detail::int128_to_double(lowest), static_cast<double>(lowest));
  EXPECT_GT(checked, 50000);
}

// ------------------------------------------------------------ the plan --

TEST(CoveragePlan, HalfTheRoomGoesToTheSlabTheRestToCrossings) {
  const Grid g = test::unit_grid(31, 17, 40);
  const std::uint64_t layer = detail::coverage_layer_bytes(g);
  EXPECT_EQ(layer, 31u * 17u * 4u + 17u * 12u);
  const std::uint64_t scene = 5000;
  const detail::CoverageSlabPlan plan = detail::plan_coverage_slabs(g, scene, scene + 8 + 10 * layer + 100);
  EXPECT_EQ(plan.layers_per_slab, 5);
  EXPECT_EQ(plan.slabs, 8);
  EXPECT_EQ(plan.crossing_room, (5 * layer + 100) / detail::coverage_crossing_bytes());
  EXPECT_LE(plan.device_bytes, scene + 8 + 10 * layer + 100);
  // A budget past the whole grid: one slab, the rest for the crossings.
  const detail::CoverageSlabPlan whole = detail::plan_coverage_slabs(g, scene, scene + 8 + 1000 * layer);
  EXPECT_EQ(whole.layers_per_slab, 40);
  EXPECT_EQ(whole.slabs, 1);
  EXPECT_EQ(whole.crossing_room, 960 * layer / detail::coverage_crossing_bytes());
  std::string message;
  EXPECT_EQ(code_of([&] { detail::plan_coverage_slabs(g, scene, scene + layer); }, &message),
            ErrorCode::limit_exceeded);
  EXPECT_NE(message.find("cannot hold the mesh (5000 bytes) and one z layer of the 31 x 17 grid"), std::string::npos)
      << message;
}

// -------------------------------------------------- the emulated device --

// The kernels' passes, whole grid at once, give the CPU's floats bit for
// bit: every sampling, four meshes (one open), odd grids.
TEST(CoverageEmulatedDevice, EqualsTheCpuBitForBitForEverySampling) {
  const std::vector<Mesh> ms = test::coverage_case_meshes();
  const std::int64_t sizes[] = {37, 29, 41, 23};
  for (std::size_t m = 0; m < ms.size(); ++m) {
    const Grid g = test::slice_case_grid(ms[m], sizes[m]);
    for (CoverageOptions o : test::coverage_cases()) {
      o.threads = 2;
      SCOPED_TRACE(describe(o) + " on mesh " + std::to_string(m));
      const DenseVolume<float> cpu = voxelize_coverage(ms[m], g, o);
      CoverageRunReport report;
      const DenseVolume<float> emulated =
          detail::voxelize_coverage_on(CoverageBackend::host_emulation, ms[m], g, o, nullptr, &report);
      EXPECT_TRUE(emulated.values() == cpu.values()) << first_difference(emulated, cpu);
      EXPECT_EQ(report.slabs, 1);
      EXPECT_GT(covered_voxels(cpu), 10.0);  // the comparison is not of empty grids
    }
  }
}

// With a budget of a few layers and little room for crossings, the grid
// goes in many slabs and each slab in several groups of rows (the emulation,
// like the GPU, refuses a pass past the room): still the CPU's floats, and
// the plan within the budget.
TEST(CoverageEmulatedDevice, SlabsAndGroupsOfRowsWithinABudgetEqualTheCpu) {
  const std::vector<Mesh> ms = test::coverage_case_meshes();
  for (std::size_t m = 0; m < 2; ++m) {
    SCOPED_TRACE("mesh " + std::to_string(m));
    const Grid g = test::slice_case_grid(ms[m], 45);
    CoverageOptions o;
    o.rays = 4;
    o.threads = 2;
    const DenseVolume<float> cpu = voxelize_coverage(ms[m], g, o);
    // Slabs of 6 layers, and as much room for crossings: a few rows' worth.
    const std::uint64_t layer = detail::coverage_layer_bytes(g);
    o.gpu_memory = detail::coverage_scene_bytes(ms[m], g) + 8 + 12 * layer;
    CoverageRunReport report;
    const DenseVolume<float> slabs =
        detail::voxelize_coverage_on(CoverageBackend::host_emulation, ms[m], g, o, nullptr, &report);
    EXPECT_TRUE(slabs.values() == cpu.values()) << first_difference(slabs, cpu);
    EXPECT_EQ(report.slabs, (g.dims.z + 5) / 6);
    EXPECT_GT(report.passes, report.slabs + 2);
    EXPECT_LE(report.gpu_bytes, o.gpu_memory);
  }
}

// Streamed, slabs of 7 layers: the CPU's slabs, in order, value for value.
TEST(CoverageEmulatedDevice, StreamedSlabsEqualTheCpuStreamedSlabs) {
  const Mesh mesh = test::coverage_case_meshes()[2];
  const Grid g = test::slice_case_grid(mesh, 33);
  CoverageOptions o;
  o.sampling = CoverageSampling::stochastic;
  o.threads = 2;
  const DenseVolume<float> cpu = voxelize_coverage(mesh, g, o);
  std::vector<std::int64_t> starts;
  std::vector<float> values;
  detail::voxelize_coverage_streamed_on(CoverageBackend::host_emulation, mesh, g, o, 7,
                                        [&](std::int64_t k0, const DenseVolume<float>& slab) {
                                          EXPECT_EQ(slab.grid().dims.z, std::min<std::int64_t>(7, g.dims.z - k0));
                                          starts.push_back(k0);
                                          values.insert(values.end(), slab.values().begin(), slab.values().end());
                                        });
  std::vector<std::int64_t> expected;
  for (std::int64_t k = 0; k < g.dims.z; k += 7) expected.push_back(k);
  EXPECT_EQ(starts, expected);
  EXPECT_TRUE(values == std::vector<float>(cpu.values().begin(), cpu.values().end()));
}

TEST(CoverageEmulatedDevice, ARowWhoseCrossingsExceedTheRoomIsRefusedSayingSo) {
  const Mesh mesh = test::coverage_case_meshes()[1];
  const Grid g = test::slice_case_grid(mesh, 40);
  CoverageOptions o;
  o.rays = 8;
  // A layer, and a layer's worth of room: a few hundred crossings, where a
  // row across the sphere has thousands.
  o.gpu_memory = detail::coverage_scene_bytes(mesh, g) + 8 + 2 * detail::coverage_layer_bytes(g);
  std::string message;
  EXPECT_EQ(code_of([&] { detail::voxelize_coverage_on(CoverageBackend::host_emulation, mesh, g, o); }, &message),
            ErrorCode::limit_exceeded);
  EXPECT_NE(message.find("crossings of its rays"), std::string::npos) << message;
  EXPECT_NE(message.find("raise the budget, lower the rays or use device cpu"), std::string::npos) << message;
}

TEST(CoverageEmulatedDevice, ReportsProgressAndHonoursCancellation) {
  const Mesh mesh = test::coverage_case_meshes()[0];
  const Grid g = test::slice_case_grid(mesh, 30);
  CoverageOptions o;
  o.gpu_memory = 4 * 1024 * 1024;
  JobControl control;
  detail::voxelize_coverage_on(CoverageBackend::host_emulation, mesh, g, o, &control);
  EXPECT_DOUBLE_EQ(control.progress(), 1.0);
  JobControl cancelled;
  cancelled.request_cancel();
  EXPECT_EQ(code_of([&] { detail::voxelize_coverage_on(CoverageBackend::host_emulation, mesh, g, o, &cancelled); }),
            ErrorCode::cancelled);
}

// ------------------------------------------------------- without a GPU --

TEST(CoverageWithoutGpu, AutoRunsOnTheCpuWithTheSameFloats) {
  ASSERT_TRUE(kGpusHidden);
  const Mesh mesh = test::coverage_case_meshes()[0];
  const Grid big = test::slice_case_grid(mesh, 160);  // past the 2^21 voxels where auto would take a GPU
  ASSERT_GE(big.voxel_count(), std::uint64_t{1} << 21);
  CoverageOptions o;
  o.rays = 2;
  o.device = ComputeDevice::automatic;
  EXPECT_EQ(coverage_device_for(o, big), ComputeDevice::cpu);
  CoverageRunReport report;
  report.device = ComputeDevice::cuda;
  const DenseVolume<float> automatic = voxelize_coverage(mesh, big, o, nullptr, &report);
  EXPECT_EQ(report.device, ComputeDevice::cpu);
  o.device = ComputeDevice::cpu;
  EXPECT_TRUE(voxelize_coverage(mesh, big, o).values() == automatic.values());
}

TEST(CoverageWithoutGpu, CudaIsRefusedSayingWhyWholeOrStreamed) {
  ASSERT_TRUE(kGpusHidden);
  const std::string& why = cuda_unavailable_reason();
  ASSERT_FALSE(why.empty());
  const Mesh mesh = test::coverage_case_meshes()[0];
  CoverageOptions o;
  o.device = ComputeDevice::cuda;
  EXPECT_EQ(coverage_device_for(o, test::slice_case_grid(mesh, 8)), ComputeDevice::cuda);
  std::string message;
  EXPECT_EQ(code_of([&] { voxelize_coverage(mesh, test::slice_case_grid(mesh, 20), o); }, &message),
            ErrorCode::invalid_argument);
  EXPECT_EQ(message, why);
  int slabs = 0;
  EXPECT_EQ(code_of([&] {
              voxelize_coverage_streamed(mesh, test::slice_case_grid(mesh, 20), o, 4,
                                         [&](std::int64_t, const DenseVolume<float>&) { ++slabs; });
            },
                    &message),
            ErrorCode::invalid_argument);
  EXPECT_EQ(message, why);
  EXPECT_EQ(slabs, 0);
}

}  // namespace
}  // namespace voxd
