#pragma once
// The signed distance field's band (voxd/voxelize/sdf.h) in the shape a GPU
// computes it, written once for the CUDA kernel (core/src/cuda/
// sdf_kernel.cu) and its host emulation (sdf_gpu.cpp), which the tests run
// on machines without a GPU. The grid is cut into bricks of 8^3 voxels;
// each brick lists the triangles whose band can reach it, and each of its
// voxels takes the least exact distance (sdf_distance.h, the CPU's own
// arithmetic) over them. The CPU scatters triangles to voxels instead, but
// its value is the same: the least of the rounded distances is the rounded
// least distance, and a voxel farther than the band from every triangle
// keeps the clamped value either way.
#include <math.h>

#include <cstdint>

#include "voxelize/host_device.h"
#include "voxelize/sdf_distance.h"

namespace voxd::sdf {

// Three doubles, trivially copyable (a GPU's shared memory holds them).
struct Vec3d {
  double x, y, z;
  Vec3d() = default;
  VOXD_HD Vec3d(double x_, double y_, double z_) : x(x_), y(y_), z(z_) {}
};
using DeviceTriangle = TriangleOf<Vec3d>;

inline constexpr int kBrick = 8;  // voxels along each side of a brick

struct SdfBandParams {
  double origin[3]{};
  double voxel_size = 1.0;
  double to_output = 1.0;  // model units -> the output unit
  float clamped = 0.0f;    // +band in the output unit
  std::int64_t dims[3]{};
  std::int64_t bricks[3]{};  // bricks along x, y, z
};

// The triangle of corners a, b, c (float model coordinates, 3 each).
VOXD_HD inline DeviceTriangle device_triangle(const float* a, const float* b, const float* c) {
  return DeviceTriangle(Vec3d(a[0], a[1], a[2]), Vec3d(b[0], b[1], b[2]), Vec3d(c[0], c[1], c[2]));
}

// Voxel (i, j, k)'s centre, as Grid::center computes it.
VOXD_HD inline Vec3d voxel_centre(const SdfBandParams& p, std::int64_t i, std::int64_t j, std::int64_t k) {
  return Vec3d(p.origin[0] + (static_cast<double>(i) + 0.5) * p.voxel_size,
               p.origin[1] + (static_cast<double>(j) + 0.5) * p.voxel_size,
               p.origin[2] + (static_cast<double>(k) + 0.5) * p.voxel_size);
}

// `best` lowered to the least squared distance from `centre` to triangles
// [triangles, triangles + count).
VOXD_HD inline double nearest2(const DeviceTriangle* triangles, int count, const Vec3d& centre, double best) {
  for (int x = 0; x < count; ++x) best = min_of(best, distance2(triangles[x], centre));
  return best;
}

// The voxel's unsigned value: its least distance in the output unit, at
// most the clamped band.
VOXD_HD inline float band_value(const SdfBandParams& p, double best2) {
  const auto d = static_cast<float>(sqrt(best2) * p.to_output);
  return d < p.clamped ? d : p.clamped;
}

}  // namespace voxd::sdf
