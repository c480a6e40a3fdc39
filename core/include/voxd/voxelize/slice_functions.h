#pragma once
// Multi-valued solid voxelization by slice functions (after Liao): every
// interior voxel (centre inside the closed mesh, exactly the solid
// voxelization of voxd/voxelize/voxelize.h with the same inside test) takes the RGBA
// colour of a slice function evaluated at its centre; exterior voxels are
// empty, RGBA (0, 0, 0, 0). Every colour a function can produce has alpha
// >= 1, so alpha > 0 is exactly the solid.
//
// The slicing frame (make_slice_frame). From the slicing direction `axis`
// (any orientation, need not be unit, not zero):
//   w = axis / |axis|
//   e = the coordinate axis x, y or z least aligned with w (smallest |w_i|,
//       the first one on a tie)
//   u = normalize(w x e),  v = w x u          (u, v, w right-handed, orthonormal)
//   o = the centre of the mesh's bounding box (voxd::bounds)
// A model point p has the frame coordinates
//   (a, b, c) = (dot(p - o, u), dot(p - o, v), dot(p - o, w)),
// c along the axis, (a, b) in the slice plane. The frame's extent [lo, hi]
// is, per coordinate, the minimum and maximum over the mesh's vertices
// (those triangles reference). Patterns follow the part: moving or rotating
// the mesh together with the axis moves or rotates the pattern and nothing
// else.
//
// Colour blending: mix(c0, c1, t) = per channel (r, g, b and a)
// floor(c0 + (c1 - c0) * t + 1/2), t in [0, 1]. A ramp of n >= 2 colours
// spread evenly, ramp(colours, t): with s = t * (n - 1), i = min(floor(s),
// n - 2): mix(colours[i], colours[i + 1], s - i).
//
// The functions, at frame coordinates (a, b, c), clamp(x) to [0, 1]:
//  - single_color:        `color`.
//  - color_ramp:          t = clamp((c - lo.c) / (hi.c - lo.c)) (0 when the
//                         extent is 0): the stop colour below the first stop
//                         and above the last one; between stops i and i + 1
//                         (the last i with position_i <= t, position_{i+1} >
//                         position_i) mix(colour_i, colour_{i+1}, (t -
//                         position_i) / (position_{i+1} - position_i)).
//                         Equal positions make a hard edge: the later stop wins.
//  - interpolated_colors: bilinear over the slice plane's extent:
//                         s = clamp((a - lo.a) / (hi.a - lo.a)),
//                         t = clamp((b - lo.b) / (hi.b - lo.b)) (0 for a zero
//                         extent), then mix(mix(corners[0], corners[1], s),
//                         mix(corners[2], corners[3], s), t): corners[0] at
//                         (lo.a, lo.b), [1] at (hi.a, lo.b), [2] at (lo.a,
//                         hi.b), [3] at (hi.a, hi.b).
//  - checker:             n = floor(a / size) + floor(b / size) + floor(c /
//                         size): checker_colors[0] for n even, [1] for n odd
//                         (cubes of edge `checker_size` in the frame).
//  - wood, marble, rock:  Perlin noise. N(q) is Ken Perlin's improved noise
//                         (2002) in 3D, roughly in [-1, 1], with its
//                         permutation table shuffled from `seed` (below);
//                         q = (a, b, c) / noise_scale; over `octaves` K:
//                           turbulence T(q) = sum_{k<K} |N(2^k q)| / 2^k
//                           fBm        F(q) = sum_{k<K}  N(2^k q)  / 2^k
//     wood:   r = sqrt(a^2 + b^2) (distance from the axis line through o),
//             t = 1/2 - 1/2 cos(2 pi (r / period + turbulence * T(q))):
//             rings `period` apart, distorted by the noise.
//     marble: t = 1/2 + 1/2 sin(2 pi c / period + 2 pi turbulence * T(q)):
//             bands across the axis, `period` apart, veined by the noise.
//     rock:   t = clamp(1/2 + 1/2 F(q)): fractal noise.
//     then ramp(noise_colors, t) (two or three colours). sin and cos here
//     are voxd's own (x reduced exactly to an eighth of a turn, then
//     fdlibm's polynomials; within 2 ulp), so that the CPU and the GPU
//     compute the same bits (core/src/voxelize/slice_shading.h).
//  - custom:              a small 3D lookup image stretched over the part's
//                         extent in the frame, nearest cell: with s, t as for
//                         interpolated_colors and u = clamp((c - lo.c) /
//                         (hi.c - lo.c)) (0 for a zero extent), the colour of
//                         cell (min(floor(s nx), nx - 1), min(floor(t ny),
//                         ny - 1), min(floor(u nz), nz - 1)), lookup_colors
//                         x fastest. Nearest, not interpolated, so a part
//                         prints in exactly the lookup's colours.
//
// Permutation of the noise: p = 0, 1, ..., 255, shuffled by Fisher-Yates with
// splitmix64 (state = seed; next: state += 0x9e3779b97f4a7c15, z = state,
// z = (z ^ z >> 30) * 0xbf58476d1ce4e5b9, z = (z ^ z >> 27) *
// 0x94d049bb133111eb, z ^ z >> 31): for i = 255 down to 1, swap p[i] and
// p[next() % (i + 1)]. No standard distribution is involved, so a seed gives
// the same pattern with every compiler and machine. Fade 6t^5 - 15t^4 +
// 10t^3 and the 12 gradient directions of the reference implementation
// (hash & 15).
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string_view>
#include <vector>

#include <glm/vec3.hpp>

#include "voxd/compute_device.h"
#include "voxd/dense_volume.h"
#include "voxd/grid.h"
#include "voxd/mesh.h"
#include "voxd/progress.h"
#include "voxd/voxelize/voxelize.h"
#include "voxd/enum_names.h"

namespace voxd {

enum class SliceFunction { single_color, color_ramp, interpolated_colors, checker, wood, marble, rock, custom };

// The contract's names.
inline constexpr EnumNames<SliceFunction, 8> kSliceFunctionNames{{
    {SliceFunction::single_color, "single_color"}, {SliceFunction::color_ramp, "color_ramp"},
    {SliceFunction::interpolated_colors, "interpolated_colors"}, {SliceFunction::checker, "checker"},
    {SliceFunction::wood, "wood"}, {SliceFunction::marble, "marble"}, {SliceFunction::rock, "rock"},
    {SliceFunction::custom, "custom"}}};
inline const char* to_string(SliceFunction function) noexcept { return name_of(kSliceFunctionNames, function); }
inline std::optional<SliceFunction> slice_function_from_string(std::string_view name) {
  return value_named(kSliceFunctionNames, name);
}

// One stop of a colour ramp: `position` in [0, 1] of the part's extent along the axis.
struct RampStop {
  double position = 0.0;
  Rgba8 color;
};

// Every colour must have alpha >= 1 (alpha 0 is an empty voxel). Only the
// fields of the chosen function are used and checked.
struct SliceOptions {
  SliceFunction function = SliceFunction::single_color;
  // Slicing direction, any orientation, need not be unit; finite, not zero.
  glm::dvec3 axis{0.0, 0.0, 1.0};

  // single_color: the colour of every interior voxel (default opaque light grey).
  Rgba8 color{200, 200, 200, 255};
  // color_ramp: 2 or more stops, positions in [0, 1], non-decreasing
  // (default blue at the low end of the axis to red at the high end).
  std::vector<RampStop> ramp{{0.0, {0, 0, 255, 255}}, {1.0, {255, 0, 0, 255}}};
  // interpolated_colors: colours at the corners of the slice plane's extent
  // (lo.a, lo.b), (hi.a, lo.b), (lo.a, hi.b), (hi.a, hi.b) (default red,
  // green, blue, white).
  std::array<Rgba8, 4> corners{{{255, 0, 0, 255}, {0, 255, 0, 255}, {0, 0, 255, 255}, {255, 255, 255, 255}}};
  // checker: the two colours (default black and white) and the cells' edge
  // in model units (> 0, default 1).
  std::array<Rgba8, 2> checker_colors{{{0, 0, 0, 255}, {255, 255, 255, 255}}};
  double checker_size = 1.0;

  // wood, marble, rock:
  std::uint64_t seed = 1;      // the noise's permutation table (any value)
  double noise_scale = 0.25;   // feature size of the noise in model units (> 0)
  int octaves = 4;             // turbulence / fBm octaves, 1..16
  double period = 0.5;         // wood ring spacing, marble band period, model units (> 0; rock ignores it)
  double turbulence = 1.0;     // how far the noise moves rings and bands, in periods (>= 0; rock ignores it)
  // Two or three colours, low to high t (default dark brown, tan, cream).
  std::vector<Rgba8> noise_colors{{92, 51, 23, 255}, {181, 130, 80, 255}, {240, 220, 180, 255}};

  // custom: the lookup image's cells along a, b, c (each 1..64) and their
  // colours, nx * ny * nz of them, x fastest (default one light grey cell).
  std::array<int, 3> lookup_dims{1, 1, 1};
  std::vector<Rgba8> lookup_colors{{200, 200, 200, 255}};

  InsideTest inside = InsideTest::parity;  // which voxels are interior (voxd/voxelize/voxelize.h)
  int threads = 0;                         // 0 = all cores
  // Where the colours are computed (voxd/compute_device.h): the same bytes
  // on either. The solid they colour is made on the CPU. automatic takes
  // the GPU for the noise functions on grids of 2^21 voxels or more, where
  // the colours cost far more than copying them back, and the CPU when the
  // GPU fails them (its memory taken by others, a CUDA error).
  ComputeDevice device = ComputeDevice::cpu;
  // Bytes of GPU memory the colouring may hold at once; grids that need
  // more go slab by slab. 0 = three quarters of the GPU's free memory.
  std::uint64_t gpu_memory = 0;
};

// What a run of voxelize_slice did, for the job's record and the benchmarks.
using SliceRunReport = DeviceRunReport;

// The device options.device resolves to for `grid`: cpu or cuda (automatic
// as above; cuda stays cuda, available or not).
ComputeDevice slice_device_for(const SliceOptions& options, const Grid& grid);

// The slicing frame of a mesh and an axis (formulas above).
struct SliceFrame {
  glm::dvec3 origin{0.0};        // o: the centre of the mesh's bounding box
  glm::dvec3 u{1.0, 0.0, 0.0};   // in-plane axes
  glm::dvec3 v{0.0, 1.0, 0.0};
  glm::dvec3 w{0.0, 0.0, 1.0};   // the unit axis
  glm::dvec3 lo{0.0}, hi{0.0};   // the mesh's extent in frame coordinates (a, b, c)

  // (a, b, c) of a model point.
  glm::dvec3 coordinates(const glm::dvec3& p) const;
};

// Throws Error(invalid_argument) for a zero or non-finite axis.
SliceFrame make_slice_frame(const Mesh& mesh, const glm::dvec3& axis);

// Throws Error(invalid_argument), naming the field and what it must be, for
// options the chosen function cannot use: a zero axis, fewer than 2 ramp
// stops or positions outside [0, 1] or decreasing, a colour with alpha 0,
// non-positive or non-finite sizes, octaves outside 1..16, a negative
// turbulence, other than 2 or 3 noise colours, lookup dims outside 1..64 or
// a colour count other than their product.
void validate(const SliceOptions& options);

// The function of `options` at a model point (formulas above): what
// voxelize_slice gives a voxel whose centre is `model_point`, up to the
// last bits of the frame coordinates (the voxelizer steps them along a row).
// Validates the options as voxelize_slice does.
Rgba8 evaluate_slice(const SliceOptions& options, const SliceFrame& frame, const glm::dvec3& model_point);

namespace detail {
struct SliceShading;
}

// The colours voxelize_slice gives the voxels of `grid`, a voxel at a time
// and with the same bits: to show a function on a solid already made (a
// section or a preview of a finished job, while its parameters are edited)
// without colouring the whole grid. voxelize_slice itself colours through
// it. Validates the options as voxelize_slice does; keeps its own copies.
class SliceColours {
 public:
  SliceColours(const SliceOptions& options, const SliceFrame& frame, const Grid& grid);
  ~SliceColours();
  SliceColours(const SliceColours&) = delete;
  SliceColours& operator=(const SliceColours&) = delete;

  const Grid& grid() const { return grid_; }
  // The colour at voxel (i, j, k)'s centre.
  Rgba8 at(std::int64_t i, std::int64_t j, std::int64_t k) const { return along_row(row_start(j, k), i); }
  // The same along a row: the frame coordinates of voxel (0, j, k)'s
  // centre, then voxel i's colour from them (the centre stepped i voxels
  // along x), as the voxelizer walks a row.
  glm::dvec3 row_start(std::int64_t j, std::int64_t k) const;
  Rgba8 along_row(const glm::dvec3& start, std::int64_t i) const;

 private:
  Grid grid_;
  std::unique_ptr<const detail::SliceShading> shading_;
};

// The coloured solid: each voxel the solid voxelization {solid,
// options.inside} fills gets the slice function at its centre, every other
// voxel (0, 0, 0, 0). Only filled voxels are evaluated. The result does not
// depend on options.threads. `control` may be null; when given, progress is
// reported (the solid the first half, the colours the second) and
// cancellation honoured (Error(cancelled)). Throws as validate does, and
// Error(invalid_argument) with cuda_unavailable_reason() when the options
// resolve to cuda where no GPU can run them, Error(limit_exceeded) when not
// even one z layer fits the GPU memory budget. `report`, when given, says
// where and how the colours were made.
DenseVolume<Rgba8> voxelize_slice(const Mesh& mesh, const Grid& grid, const SliceOptions& options,
                                  JobControl* control = nullptr, SliceRunReport* report = nullptr);

}  // namespace voxd
