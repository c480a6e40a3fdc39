#pragma once
// Direct surface rendering of a signed distance field (Jones 1996, after
// Hart's sphere tracing): each pixel's orthographic ray marches through the
// field by the distance it reads, finds the zero level set to a fraction of
// a voxel, and is lit with the field's gradient as the normal. Unlike the
// voxel preview (voxd/analysis/preview.h), the surface is the field's smooth
// interpolant, not voxel faces, so a sphere looks round at any resolution.
//
// Field: trilinear interpolation of the voxel-centre values (positions
// outside the centres' box take the nearest boundary value), in voxels and
// inside negative whatever the input's units and sign convention (the values
// are multiplied by +-1 / units_per_voxel on the fly; the negation is exact,
// so both conventions render to the same bits).
//
// Marching: from the camera side of the grid box, every sample on a lattice
// of 1/16 voxel along the ray: a step of d (the interpolated distance, in
// voxels) rounded down to the lattice, at least one lattice step, and single
// lattice steps where d < 1 voxel. A clamped value (+-band outside a narrow
// band) is at most the true distance, so it is still a safe step. The first
// lattice point at or below 0 brackets the crossing with the lattice point
// before it; 24 bisections and a linear interpolation inside the last
// interval put the hit within about 1e-8 voxel of the interpolant's zero.
// Near the surface every lattice point is sampled whatever the path that led
// there, so a field clamped to a band of at least 3 voxels renders to the
// same bits as the full field (the values within about 2 voxels of the
// surface are the same). A negative sliver of the interpolant shorter than
// 1/16 voxel between lattice points can be missed (a ray grazing an edge).
// NaN values count as outside; a distance longer than the rest of the ray
// (FLT_MAX, +inf) ends it.
// A ray that enters the grid inside the part (the part is cut by the grid
// box) hits at its entry point and is lit as a face towards the camera.
//
// Normals: central differences of the voxel values at the 8 voxel centres
// around the hit (one-sided at the grid's faces), trilinearly interpolated
// and normalised (outward, towards increasing distance), so shading is
// continuous across cells; a linear field gives its exact gradient.
//
// Shading (Phong; L = normalize(-f + 0.5 up - 0.35 right) from the viewer's
// upper left as in the voxel preview, V = -f towards the camera, R the
// reflection of L about n):
//   shade    = 0.2 + 0.7 max(0, n.L)           (ambient + diffuse)
//   specular = 0.3 max(0, R.V)^24 when n.L > 0
//   colour   = kPreviewPartColour * shade + 255 * specular, clamped to 255.
// No depth cueing. Background white.
//
// Image: one pixel per voxel along the view's right and up axes
// (voxd/analysis/preview.h's view_basis: the same orientation and size as the voxel
// preview), or pixels_per_voxel x that (1..8), pixel (c, r) sampled at its
// centre, so with 1 pixel per voxel each ray runs along a column of voxel
// centres.
//
// Cost: one trilinear sample per step (a band-clamped field gives steps of
// about the band far from the part), 16 per voxel of ray within a voxel of
// the surface, 26 more per hit; bench/sdf_render_bench.cpp.
#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "voxd/dense_volume.h"
#include "voxd/encode/png_image.h"
#include "voxd/analysis/preview.h"
#include "voxd/voxelize/sdf.h"

namespace voxd {

// A signed distance field and how to read it.
struct SdfRenderInput {
  const DenseVolume<float>* sdf = nullptr;
  bool inside_negative = true;   // false: values are positive inside the part
  double units_per_voxel = 1.0;  // value of one voxel of distance: the grid's voxel_size for model units, 1 for voxels
  std::string unit = "voxel";    // the values' unit, for labels and tEXt ("model units", "voxel")
};

// The input for a field made by signed_distance_field(mesh, grid, options):
// the sign convention and units of `options`.
SdfRenderInput sdf_render_input(const DenseVolume<float>& sdf, const SdfOptions& options);

struct SdfRenderImage {
  int width = 0, height = 0;     // dims[right_axis] * pixels_per_voxel, dims[up_axis] * pixels_per_voxel
  int pixels_per_voxel = 1;
  // Per pixel, row-major (row 0 at the top):
  std::vector<glm::dvec3> hit;     // the surface point in model coordinates; NaN in all three for background
  std::vector<glm::vec3> normal;   // unit outward normal (world axes); zero for background
  std::vector<float> shade;        // ambient + diffuse factor in [0.2, 0.9]; 0 for background
  std::vector<float> specular;     // specular term in [0, 0.3]; 0 for background
  RgbImage image;                  // the shaded picture, as sdf_preview_png encodes it
};

// Renders the field from `view`. `threads` 0 = all cores; rows are split
// among threads and each pixel is computed alone, so the result does not
// depend on it. Throws Error(invalid_argument) for a null field, a grid with
// a zero dimension, units_per_voxel not a positive finite number,
// pixels_per_voxel outside 1..8 or a view axis outside 0..2, and
// Error(limit_exceeded) for an image over 2^26 pixels (about 47 bytes each).
SdfRenderImage render_sdf(const SdfRenderInput& input, View view, int threads = 0, int pixels_per_voxel = 1);

// The render as 8-bit RGB PNG. tEXt: voxd:view, voxd:right, voxd:up,
// voxd:voxel_size (model units per pixel), voxd:pixels_per_voxel,
// voxd:lighting, voxd:render = "sdf sphere tracing", then `text`. Throws as
// render_sdf(). `max_side` > 0 shrinks a larger image as preview_png does
// (each pixel its block's nearest hit; voxd:shrunk says so).
std::vector<std::uint8_t> sdf_preview_png(const SdfRenderInput& input, View view, std::vector<PngText> text = {},
                                          int threads = 0, int pixels_per_voxel = 1, int max_side = 0);

}  // namespace voxd
