#pragma once
// Signed distance field of a triangle mesh on the voxel grid: at every voxel
// centre, the Euclidean distance to the nearest point of the mesh surface,
// signed by the solid voxelization (the voxel is inside when
// voxelize(mesh, grid, {solid, options.inside}) fills it).
//
// Narrow band (Jones 1996: exact distances are only needed near the surface).
// Triangles are scattered to the voxels whose centres lie within the band of
// them, and each voxel keeps the smallest exact point-triangle distance it
// receives. A voxel whose distance is at most band * voxel_size is reached by
// its nearest triangle, so its value is exact; every other voxel holds +-band
// (clamped). Neighbouring small triangles go as a cluster (one visit per voxel
// for the cluster, one bound for all its triangles, then exact distances in
// order of their lower bounds), after a first pass has given each voxel an
// upper bound from the triangles' centroids, so that few exact distances are
// computed that do not win. Threads own disjoint chunks of z-slabs, each with
// the clusters whose band reaches it, so no two threads write one voxel and
// the result does not depend on the thread count.
//
// Full field (`full`): the voxels the band leaves clamped get exact nearest-
// triangle queries in a bounding volume hierarchy. Not a propagation of the
// band's nearest triangles outward (which is only approximately right, the
// classic vector-propagation error): every query proves its answer, pruning
// only subtrees whose lower bound is not below the best distance found. The
// bounds are boxes oriented along each node's mean normal, which stay tight
// along a smooth surface seen from afar, where axis-aligned boxes leave many
// near ties open. Each query starts from the previous voxel's nearest
// triangle and distance (d is 1-Lipschitz), so it usually only confirms.
//
// Precision: geometry in double, one rounding to float at the end (the
// minimum of the rounded distances is the rounded minimum), so each value is
// the exact distance rounded to float: a brute force over all triangles with
// point_triangle_distance2 gives the same bits.
//
// Cost: the band is about (2 band + 1)^3 voxel visits per cluster of about a
// dozen triangles (per triangle where they are large or folded), most
// settled by the cluster's oriented box; the full field adds a tree
// query per voxel outside the band, a few microseconds each on a million
// triangles (bench/sdf_bench.cpp). Memory: the float result, the solid's bit
// per voxel and the triangle bins; with `full`, the hierarchy (about 70
// bytes per triangle, 120 while it is built).
#include <functional>
#include <optional>
#include <string>

#include <glm/vec3.hpp>

#include "voxd/compute_device.h"
#include "voxd/dense_volume.h"
#include "voxd/grid.h"
#include "voxd/mesh.h"
#include "voxd/progress.h"
#include "voxd/encode/slab_writer.h"
#include "voxd/run_slab.h"
#include "voxd/voxelize/voxelize.h"
#include "voxd/enum_names.h"

namespace voxd {

enum class SignConvention { inside_negative, inside_positive };
inline constexpr EnumNames<SignConvention, 2> kSignConventionNames{{
    {SignConvention::inside_negative, "inside_negative"}, {SignConvention::inside_positive, "inside_positive"}}};
inline const char* to_string(SignConvention sign) noexcept { return name_of(kSignConventionNames, sign); }

struct SdfOptions {
  // Half-width of the band in voxels: exact distances where |d| <= band *
  // voxel_size; elsewhere the value is +-band (clamped), in the output unit.
  double band = 3.0;
  bool full = false;  // exact distances on the whole grid too (the band is still computed first)
  SignConvention sign = SignConvention::inside_negative;
  bool model_units = true;                 // false: values in voxels (distance / voxel_size)
  InsideTest inside = InsideTest::parity;  // the solid that gives the sign
  int threads = 0;                         // 0 = all cores
  // Where the band is computed (voxd/compute_device.h): the same bits on
  // either; the solid that signs it and the full field's queries are made
  // on the CPU. automatic takes the GPU for grids of 2^21 voxels or more and
  // the CPU when the GPU fails them (its memory taken by others, a CUDA
  // error). Slab by slab (signed_distance_field_slabs) is the CPU's alone.
  ComputeDevice device = ComputeDevice::cpu;
  // Bytes of GPU memory the band may hold at once; grids that need more go
  // slab by slab. 0 = three quarters of the GPU's free memory.
  std::uint64_t gpu_memory = 0;
};

// The device options.device resolves to for `grid`: cpu or cuda (automatic
// as above; cuda stays cuda, available or not).
ComputeDevice sdf_device_for(const SdfOptions& options, const Grid& grid);

// Throws Error(invalid_argument) when band is not a positive finite number
// (or the grid's voxel size is not). `control` may be null; when given,
// progress goes from 0 to 1 and cancellation (Error(cancelled)) is honoured.
// A voxel centre on the surface gets +0 whatever its side. A mesh without
// triangles has no surface to measure: +band everywhere, also with `full`.
DenseVolume<float> signed_distance_field(const Mesh& mesh, const Grid& grid, const SdfOptions& options,
                                         JobControl* control = nullptr);
// The same, also handing back in `solid` the solid voxelization that signed
// it, voxelize(mesh, grid, {solid, options.inside}), so a caller that needs
// both (a job keeps the solid for its analyses) voxelizes once, and in
// `report` where the band was computed. Either may be null.
DenseVolume<float> signed_distance_field(const Mesh& mesh, const Grid& grid, const SdfOptions& options,
                                         JobControl* control, BitVolume* solid, DeviceRunReport* report = nullptr);

// The band slab by slab, for outputs written as they come (an RLE, where the
// clamped background is a handful of runs): never the whole float volume,
// whose fresh pages alone cost about as much as the band (0.4 GB at 512^3).
// Why options cannot (the full field, the vote or winding sign, device
// cuda), else nullopt.
std::optional<std::string> sdf_slabs_refusal(const SdfOptions& options);
// First the solid that signs the field, as runs (every layer, in z order, to
// `solid`), then the field's slabs (to `values`, each a DenseVolume<float>
// reused after the call returns): bit for bit
// signed_distance_field's. Memory: the solid's runs, the band's clusters and
// a few slabs. Throws Error(invalid_argument) where sdf_slabs_refusal says.
void signed_distance_field_slabs(const Mesh& mesh, const Grid& grid, const SdfOptions& options,
                                 const RunSlabConsumer& solid, const ValueSlabConsumer& values,
                                 JobControl* control = nullptr);


// Exact squared distance from p to the triangle (a, b, c), in double: the
// face, edge and vertex regions of Ericson, Real-Time Collision Detection
// 5.1.5, told apart by signed distances to the edge lines instead of the
// book's products of dot products, which cancel on thin triangles; the face
// region's distance is taken from the plane. Degenerate triangles (zero
// area: segments, points) are measured to their edges. The tests hold it to
// 1e-9 relative of a long-double brute force, slivers included.
double point_triangle_distance2(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c);

}  // namespace voxd
