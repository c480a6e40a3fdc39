#pragma once
// Anti-aliased grey voxelization (Thon, Gesquiere & Raffin 2004): each voxel
// gets the fraction of its volume inside the closed mesh, estimated from
// k x k rays per voxel column along x.
//
// Sampling:
//  - exact (default): k x k rays on a regular pattern inside each column
//    (at offsets (a + 1/2) / k), and along each ray the inside length within
//    every voxel integrated exactly from the ray's sorted crossings. Only the
//    ray placement is sampled, so a half-space or a box face whose normal is
//    x comes out exact, and the estimate converges as 1/k^2 in the cross
//    section only.
//  - uniform: the paper's k x k x m: the same rays, m evenly spaced points per
//    voxel along each ray, each counted inside or out.
//  - stochastic: k x k rays, one at a random place in each of the column's
//    k x k cells (jittered; the seed makes runs repeat), integrated exactly.
// Crossings are exact: ray positions are snapped to the engine's fixed-point
// lattice (2^-20 voxel, voxelize/fixed_point_mesh.h) and tested against
// triangles with integer edge functions, ties broken by simulation of
// simplicity as in the parity voxelizer, so a ray through a shared edge or
// vertex of a closed mesh crosses it exactly once. Interior runs are filled
// per column once, whatever k: the work is the crossings plus the voxels
// inside.
#include <cstdint>
#include <functional>

#include "voxd/bit_volume.h"
#include "voxd/compute_device.h"
#include "voxd/dense_volume.h"
#include "voxd/grid.h"
#include "voxd/mesh.h"
#include "voxd/progress.h"
#include "voxd/enum_names.h"

namespace voxd {

enum class CoverageSampling { exact, uniform, stochastic };
inline constexpr EnumNames<CoverageSampling, 3> kCoverageSamplingNames{{
    {CoverageSampling::exact, "exact"}, {CoverageSampling::uniform, "uniform"},
    {CoverageSampling::stochastic, "stochastic"}}};
inline const char* to_string(CoverageSampling sampling) noexcept { return name_of(kCoverageSamplingNames, sampling); }

struct CoverageOptions {
  CoverageSampling sampling = CoverageSampling::exact;
  int rays = 4;             // k: k x k rays per voxel column, 1..64
  int points = 4;           // m: points per voxel along a ray (uniform only), 1..256
  std::uint64_t seed = 1;   // stochastic ray placement
  int threads = 0;          // 0 = all cores
  // Where the coverages are computed (voxd/compute_device.h): the same
  // floats, bit for bit, on either. automatic takes the GPU for grids of
  // 2^21 voxels or more and the CPU when the GPU fails them (its memory
  // taken by others, a CUDA error).
  ComputeDevice device = ComputeDevice::cpu;
  // Bytes of GPU memory the work may hold at once; grids that need more go
  // slab by slab. 0 = three quarters of the GPU's free memory.
  std::uint64_t gpu_memory = 0;
};

// Throws Error(invalid_argument), naming the option, for rays or points out
// of range.
void validate(const CoverageOptions& options);

// What a run of the coverage voxelizer did (where, and on a GPU how).
using CoverageRunReport = DeviceRunReport;

// The device options.device resolves to for `grid`: cpu or cuda (automatic
// as above; cuda stays cuda, available or not).
ComputeDevice coverage_device_for(const CoverageOptions& options, const Grid& grid);

// Coverage in [0, 1] per voxel. Throws Error(invalid_argument) for rays or
// points out of range, and for device cuda where cuda_unavailable_reason()
// is not empty. `control` and `report` may be null.
DenseVolume<float> voxelize_coverage(const Mesh& mesh, const Grid& grid, const CoverageOptions& options,
                                     JobControl* control = nullptr, CoverageRunReport* report = nullptr);

// voxelize_coverage() slab by slab in z order (Thon et al.'s "limited only by
// disk size"): each slab of `slab_layers` z layers (the last one shorter) is
// handed to `consume` as soon as it is final, its values exactly
// voxelize_coverage()'s for those layers, and its memory reused after. Peak
// memory is the mesh, its triangle bins and one slab of floats. Throws as
// voxelize_coverage(); progress runs over the rows, cancellation between them.
// On a GPU a slab is at most what its memory budget holds.
using CoverageSlabConsumer = std::function<void(std::int64_t k0, const DenseVolume<float>& slab)>;
void voxelize_coverage_streamed(const Mesh& mesh, const Grid& grid, const CoverageOptions& options,
                                std::int64_t slab_layers, const CoverageSlabConsumer& consume,
                                JobControl* control = nullptr, CoverageRunReport* report = nullptr);

// Thon's byte: round(255 * coverage). `threads` 0 = all cores.
DenseVolume<std::uint8_t> coverage_bytes(const DenseVolume<float>& coverage, int threads = 0);

// The sum of the coverages, in voxels (times the voxel volume: the volume
// the grey levels measure). Summed per slab in double, the slabs added in
// order, so the total does not depend on `threads` (0 = all cores).
double covered_voxels(const DenseVolume<float>& coverage, int threads = 0);
// The same sum over slabs that arrive in z order: add() each, then total();
// exactly covered_voxels() of the whole (it adds layer sums in layer order).
class CoveredVoxels {
 public:
  void add(const DenseVolume<float>& slab, int threads = 0);
  double total() const { return total_; }

 private:
  double total_ = 0.0;
};

// The binary volume of the voxels with coverage >= threshold (Thon: keeps
// features thinner than a voxel that centre sampling loses, with a threshold
// below 1/2). Throws Error(invalid_argument) unless 0 < threshold <= 1.
BitVolume coverage_threshold(const DenseVolume<float>& coverage, float threshold);

}  // namespace voxd
