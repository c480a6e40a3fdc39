#pragma once
// The arithmetic of the slice functions (voxd/voxelize/slice_functions.h),
// written once for the CPU and the GPU: the C++ compiler builds it into the
// CPU path and nvcc into the CUDA kernel (core/src/cuda/slice_kernel.cu),
// so both colour a voxel with the same IEEE operations in the same order.
// What keeps the bits equal:
//  - no contraction into fused multiply-adds on either side (the CPU build
//    targets x86-64-v2, which has no FMA; the kernel is compiled with
//    -fmad=false);
//  - only correctly rounded operations (+ - * /, sqrt) and exact ones
//    (floor, fmod, fabs, rint, conversions) from the C library or CUDA;
//  - sine and cosine, which neither library rounds correctly nor alike,
//    computed here: sin_turns / cos_turns below.
// Plain data only (no std::vector, no glm), so the kernel takes its
// parameters by value and a host emulation of the kernel
// (slice_device.h) runs the very same code.
#include <math.h>

#include <cstdint>

#include "voxelize/host_device.h"

namespace voxd::detail {

// An RGBA8 colour, laid out as voxd::Rgba8.
struct ShadeColour {
  std::uint8_t r, g, b, a;
};

struct ShadeRampStop {
  double position;
  ShadeColour color;
};

// The function's numbers, prepared once on the host (reciprocals). Pointers
// are to its tables (ramp stops, lookup colours, the noise's permutation)
// wherever the shading runs (host or device memory).
struct SliceShadeParams {
  int function = 0;  // voxd::SliceFunction
  ShadeColour color{};
  ShadeColour corners[4]{};
  ShadeColour checker[2]{};
  ShadeColour noise_colors[3]{};
  int noise_count = 2;
  const ShadeRampStop* ramp = nullptr;
  int ramp_count = 0;
  const ShadeColour* lookup = nullptr;
  int lookup_dims[3]{1, 1, 1};
  double lo[3]{};          // the frame's extent's low corner (a, b, c)
  double inv_extent[3]{};  // 1 / (hi - lo), 0 for a zero extent
  double inv_cell = 1.0, inv_scale = 1.0, inv_period = 1.0, turbulence = 0.0;
  int octaves = 1;
  const std::uint8_t* perm = nullptr;  // the noise's permutation, twice over (512 entries)
};

// Where voxel centres lie in the slicing frame.
struct SliceVoxelFrame {
  double grid_origin[3]{};
  double voxel_size = 1.0;
  double frame_origin[3]{};
  double u[3]{}, v[3]{}, w[3]{};
  double step[3]{};  // voxel_size * (u.x, v.x, w.x): one voxel along x in frame coordinates
};

// The function numbers of voxd::SliceFunction, in its order.
enum : int {
  kShadeSingleColor,
  kShadeColorRamp,
  kShadeInterpolatedColors,
  kShadeChecker,
  kShadeWood,
  kShadeMarble,
  kShadeRock,
  kShadeCustom
};

// --- sin(2 pi x) and cos(2 pi x) -------------------------------------------
// x is reduced exactly to f in [-1/8, 1/8] and a quadrant q (x = n + q/4 + f,
// n an integer), then fdlibm's kernels (Sun Microsystems, 1993; freely
// distributable) give sin and cos of 2 pi f, |2 pi f| <= pi/4. Within 2 ulp
// of the true value (tests/core/slice_shading_test.cpp measures it against
// the C library), the same bits on every machine. A non-finite x gives 0.

inline constexpr double kShadeTwoPi = 6.28318530717958647692;

VOXD_HD inline double kernel_sin(double x) {
  const double S1 = -1.66666666666666324348e-01, S2 = 8.33333333332248946124e-03,
               S3 = -1.98412698298579493134e-04, S4 = 2.75573137070700676789e-06,
               S5 = -2.50507602534068634195e-08, S6 = 1.58969099521155010221e-10;
  const double z = x * x;
  const double v = z * x;
  const double r = S2 + z * (S3 + z * (S4 + z * (S5 + z * S6)));
  return x + v * (S1 + z * r);
}

VOXD_HD inline double kernel_cos(double x) {
  const double C1 = 4.16666666666666019037e-02, C2 = -1.38888888888741095749e-03,
               C3 = 2.48015872894767294178e-05, C4 = -2.75573143513906633035e-07,
               C5 = 2.08757232129817482790e-09, C6 = -1.13596475577881948265e-11;
  const double z = x * x;
  const double r = z * (C1 + z * (C2 + z * (C3 + z * (C4 + z * (C5 + z * C6)))));
  const double hz = 0.5 * z;
  const double w = 1.0 - hz;
  return w + (((1.0 - w) - hz) + z * r);
}

// x = n + q/4 + f exactly; returns q mod 4, sets theta = 2 pi f.
VOXD_HD inline int reduce_turns(double x, double& theta) {
  const double r = x - rint(x);          // [-1/2, 1/2], exact
  const double q = rint(4.0 * r);        // -2..2
  theta = (r - 0.25 * q) * kShadeTwoPi;  // r - q/4 exact, |.| <= 1/8
  return static_cast<int>(q) & 3;
}

VOXD_HD inline double sin_turns(double x) {
  if (!isfinite(x)) return 0.0;
  double t;
  switch (reduce_turns(x, t)) {
    case 0: return kernel_sin(t);
    case 1: return kernel_cos(t);
    case 2: return -kernel_sin(t);
    default: return -kernel_cos(t);
  }
}

VOXD_HD inline double cos_turns(double x) {
  if (!isfinite(x)) return 0.0;
  double t;
  switch (reduce_turns(x, t)) {
    case 0: return kernel_cos(t);
    case 1: return -kernel_sin(t);
    case 2: return -kernel_cos(t);
    default: return kernel_sin(t);
  }
}

// --- Improved noise (Perlin 2002) ------------------------------------------

VOXD_HD inline double noise_fade(double t) { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); }
VOXD_HD inline double noise_lerp(double t, double a, double b) { return a + t * (b - a); }

// Dot product with one of the 12 edge directions of the cube (hash & 15).
VOXD_HD inline double noise_grad(int hash, double x, double y, double z) {
  const int h = hash & 15;
  const double u = h < 8 ? x : y;
  const double v = h < 4 ? y : (h == 12 || h == 14) ? x : z;
  return ((h & 1) == 0 ? u : -u) + ((h & 2) == 0 ? v : -v);
}

// floor(x) as the lattice cell (mod 256) and the offset in the cell. The
// integer path is exact and fast while |x| < 2^30; beyond, the table repeats
// every 256 cells anyway.
VOXD_HD inline int noise_cell(double x, double& offset) {
  if (fabs(x) < 1073741824.0) {
    int i = static_cast<int>(x);
    if (x < static_cast<double>(i)) --i;
    offset = x - static_cast<double>(i);
    return i & 255;
  }
  const double f = floor(x);
  offset = x - f;
  return static_cast<int>(fmod(f, 256.0) + (f < 0 ? 256.0 : 0.0)) & 255;
}

VOXD_HD inline double perlin_noise(const std::uint8_t* p, double x, double y, double z) {
  const int X = noise_cell(x, x), Y = noise_cell(y, y), Z = noise_cell(z, z);
  const double u = noise_fade(x), v = noise_fade(y), w = noise_fade(z);
  const int A = p[X] + Y, AA = p[A] + Z, AB = p[A + 1] + Z;
  const int B = p[X + 1] + Y, BA = p[B] + Z, BB = p[B + 1] + Z;
  return noise_lerp(
      w,
      noise_lerp(v, noise_lerp(u, noise_grad(p[AA], x, y, z), noise_grad(p[BA], x - 1, y, z)),
                 noise_lerp(u, noise_grad(p[AB], x, y - 1, z), noise_grad(p[BB], x - 1, y - 1, z))),
      noise_lerp(v, noise_lerp(u, noise_grad(p[AA + 1], x, y, z - 1), noise_grad(p[BA + 1], x - 1, y, z - 1)),
                 noise_lerp(u, noise_grad(p[AB + 1], x, y - 1, z - 1), noise_grad(p[BB + 1], x - 1, y - 1, z - 1))));
}

// T = sum_{k<octaves} |N(2^k q)| / 2^k.
VOXD_HD inline double noise_turbulence(const std::uint8_t* p, double x, double y, double z, int octaves) {
  double sum = 0.0, f = 1.0;
  for (int k = 0; k < octaves; ++k, f *= 2.0) sum += fabs(perlin_noise(p, x * f, y * f, z * f)) / f;
  return sum;
}

// F = sum_{k<octaves} N(2^k q) / 2^k.
VOXD_HD inline double noise_fbm(const std::uint8_t* p, double x, double y, double z, int octaves) {
  double sum = 0.0, f = 1.0;
  for (int k = 0; k < octaves; ++k, f *= 2.0) sum += perlin_noise(p, x * f, y * f, z * f) / f;
  return sum;
}

// --- Colours ---------------------------------------------------------------

VOXD_HD inline double shade_clamp01(double t) { return t > 0.0 ? (t < 1.0 ? t : 1.0) : 0.0; }

// mix(c0, c1, t) per channel: floor(c0 + (c1 - c0) t + 1/2), t in [0, 1].
VOXD_HD inline std::uint8_t mix_channel(std::uint8_t c0, std::uint8_t c1, double t) {
  const double a = c0;
  return static_cast<std::uint8_t>(static_cast<int>(a + (static_cast<double>(c1) - a) * t + 0.5));
}

VOXD_HD inline ShadeColour mix_colours(const ShadeColour& c0, const ShadeColour& c1, double t) {
  return {mix_channel(c0.r, c1.r, t), mix_channel(c0.g, c1.g, t), mix_channel(c0.b, c1.b, t),
          mix_channel(c0.a, c1.a, t)};
}

// The bilinear value of four corner channels, in doubles, rounded once.
VOXD_HD inline std::uint8_t bilinear_channel(std::uint8_t c0, std::uint8_t c1, std::uint8_t c2, std::uint8_t c3,
                                             double s, double t) {
  const double bottom = c0 + (static_cast<double>(c1) - c0) * s;
  const double top = c2 + (static_cast<double>(c3) - c2) * s;
  return static_cast<std::uint8_t>(static_cast<int>(bottom + (top - bottom) * t + 0.5));
}

// ramp(colours, t): n colours spread evenly over [0, 1].
VOXD_HD inline ShadeColour ramp_even(const SliceShadeParams& p, double t) {
  const double s = t * static_cast<double>(p.noise_count - 1);
  std::uint64_t i = static_cast<std::uint64_t>(s);
  const std::uint64_t last = static_cast<std::uint64_t>(p.noise_count - 2);
  if (i > last) i = last;
  return mix_colours(p.noise_colors[i], p.noise_colors[i + 1], s - static_cast<double>(i));
}

VOXD_HD inline ShadeColour ramp_stops(const SliceShadeParams& p, double t) {
  const ShadeRampStop* s = p.ramp;
  const int n = p.ramp_count;
  if (t < s[0].position) return s[0].color;
  if (t >= s[n - 1].position) return s[n - 1].color;
  int i = 0;
  while (i + 1 < n && s[i + 1].position <= t) ++i;
  // s[i].position <= t < s[i + 1].position
  return mix_colours(s[i].color, s[i + 1].color, (t - s[i].position) / (s[i + 1].position - s[i].position));
}

// The function at frame coordinates (a, b, c).
VOXD_HD inline ShadeColour slice_shade(const SliceShadeParams& p, double a, double b, double c) {
  switch (p.function) {
    case kShadeSingleColor: return p.color;
    case kShadeColorRamp: return ramp_stops(p, shade_clamp01((c - p.lo[2]) * p.inv_extent[2]));
    case kShadeInterpolatedColors: {
      const double s = shade_clamp01((a - p.lo[0]) * p.inv_extent[0]);
      const double t = shade_clamp01((b - p.lo[1]) * p.inv_extent[1]);
      const ShadeColour* k = p.corners;
      return {bilinear_channel(k[0].r, k[1].r, k[2].r, k[3].r, s, t),
              bilinear_channel(k[0].g, k[1].g, k[2].g, k[3].g, s, t),
              bilinear_channel(k[0].b, k[1].b, k[2].b, k[3].b, s, t),
              bilinear_channel(k[0].a, k[1].a, k[2].a, k[3].a, s, t)};
    }
    case kShadeChecker: {
      const double n = floor(a * p.inv_cell) + floor(b * p.inv_cell) + floor(c * p.inv_cell);
      return p.checker[fmod(n, 2.0) == 0.0 ? 0 : 1];
    }
    case kShadeWood: {
      const double r = sqrt(a * a + b * b);
      const double T = noise_turbulence(p.perm, a * p.inv_scale, b * p.inv_scale, c * p.inv_scale, p.octaves);
      return ramp_even(p, 0.5 - 0.5 * cos_turns(r * p.inv_period + p.turbulence * T));
    }
    case kShadeMarble: {
      const double T = noise_turbulence(p.perm, a * p.inv_scale, b * p.inv_scale, c * p.inv_scale, p.octaves);
      return ramp_even(p, 0.5 + 0.5 * sin_turns(c * p.inv_period + p.turbulence * T));
    }
    case kShadeRock: {
      const double F = noise_fbm(p.perm, a * p.inv_scale, b * p.inv_scale, c * p.inv_scale, p.octaves);
      return ramp_even(p, shade_clamp01(0.5 + 0.5 * F));
    }
    case kShadeCustom: {
      std::uint64_t index = 0, stride = 1;
      const double abc[3] = {a, b, c};
      for (int i = 0; i < 3; ++i) {
        const int n = p.lookup_dims[i];
        const double t = shade_clamp01((abc[i] - p.lo[i]) * p.inv_extent[i]);
        std::uint64_t cell = static_cast<std::uint64_t>(t * n);
        if (cell > static_cast<std::uint64_t>(n - 1)) cell = static_cast<std::uint64_t>(n - 1);
        index += cell * stride;
        stride *= static_cast<std::uint64_t>(n);
      }
      return p.lookup[index];
    }
    default: return p.color;
  }
}

// --- Voxel centres in the frame ---------------------------------------------

// The frame coordinates of voxel (0, j, k)'s centre: Grid::center, then
// SliceFrame::coordinates, operation for operation.
VOXD_HD inline void slice_row_start(const SliceVoxelFrame& f, std::int64_t j, std::int64_t k, double out[3]) {
  const double p[3] = {f.grid_origin[0] + (0.0 + 0.5) * f.voxel_size,
                       f.grid_origin[1] + (static_cast<double>(j) + 0.5) * f.voxel_size,
                       f.grid_origin[2] + (static_cast<double>(k) + 0.5) * f.voxel_size};
  const double d[3] = {p[0] - f.frame_origin[0], p[1] - f.frame_origin[1], p[2] - f.frame_origin[2]};
  out[0] = d[0] * f.u[0] + d[1] * f.u[1] + d[2] * f.u[2];
  out[1] = d[0] * f.v[0] + d[1] * f.v[1] + d[2] * f.v[2];
  out[2] = d[0] * f.w[0] + d[1] * f.w[1] + d[2] * f.w[2];
}

// Voxel i's colour from its row's start: the centre stepped i voxels along x.
VOXD_HD inline ShadeColour slice_along_row(const SliceShadeParams& p, const SliceVoxelFrame& f, const double start[3],
                                           std::int64_t i) {
  const double x = static_cast<double>(i);
  return slice_shade(p, start[0] + x * f.step[0], start[1] + x * f.step[1], start[2] + x * f.step[2]);
}

// One voxel of a slab of z layers: its colour where the solid's bit is set,
// (0, 0, 0, 0) elsewhere. `bits` holds the slab's rows (row_words words
// each, y then z), `index` runs over the slab's voxels x fastest; the slab's
// first layer is k0. The kernel runs this for every voxel of a slab.
VOXD_HD inline void colour_slab_voxel(const SliceShadeParams& p, const SliceVoxelFrame& f, const std::uint64_t* bits,
                                      std::int64_t row_words, std::int64_t nx, std::int64_t ny, std::int64_t k0,
                                      std::int64_t index, ShadeColour* out) {
  const std::int64_t i = index % nx;
  const std::int64_t row = index / nx;  // j + ny * (k - k0)
  const std::int64_t j = row % ny;
  const std::int64_t k = k0 + row / ny;
  if ((bits[row * row_words + (i >> 6)] >> (i & 63)) & 1u) {
    double start[3];
    slice_row_start(f, j, k, start);
    out[index] = slice_along_row(p, f, start, i);
  } else {
    out[index] = ShadeColour{0, 0, 0, 0};
  }
}

}  // namespace voxd::detail
