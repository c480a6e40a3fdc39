#pragma once
// Shaded preview of a voxel model: an orthographic view along a grid axis,
// each pixel showing the first filled voxel the viewing ray meets, lit with a
// surface normal estimated from that voxel's neighbour configuration (Patil &
// Ravi: the empty voxels among the 26 neighbours point away from the solid,
// so the sum of their unit offsets approximates the outward normal).
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <glm/vec3.hpp>

#include "voxd/bit_volume.h"
#include "voxd/run_slab.h"

namespace voxd {

// Orthographic view along an axis. "+z": camera on the +z side of the part looking towards -z (sees the top).
struct View {
  int axis = 2;
  bool from_positive = true;
};
// "+x", "-x", "+y", "-y", "+z", "-z" (and "x", "y", "z" meaning +); anything else nullopt.
std::optional<View> parse_view(std::string_view text);
// "+z" etc. Throws Error(invalid_argument) for an axis outside 0..2.
std::string to_string(View v);

// Image axes of a view: columns run along `right`, rows run from `up` (row 0 =
// largest coordinate along up) downwards. Right-handed (right x up points at
// the camera), so the image is never mirrored:
//   +z: right +x, up +y   -z: right -x, up +y
//   +x: right +y, up +z   -x: right -y, up +z
//   +y: right -x, up +z   -y: right +x, up +z
struct ViewBasis {
  int right_axis;
  bool right_positive;
  int up_axis;
  bool up_positive;
};
// Throws Error(invalid_argument) for an axis outside 0..2.
ViewBasis view_basis(View v);

struct PreviewImage {
  int width = 0, height = 0;        // width = dims[right_axis], height = dims[up_axis], over block
  int block = 1;                    // each pixel a block x block of voxel-sized ones (shrink_preview)
  std::vector<std::int64_t> voxel;  // per pixel (row-major): linear index i + nx*(j + ny*k) of the visible voxel, -1 = background
  std::vector<float> shade;         // per pixel: lighting factor in [0, 1]; 0 for background
  std::vector<glm::vec3> normal;    // per pixel: unit normal used for lighting (world axes), zero for background
};

// Normals: the neighbour-configuration normal of each visible voxel (the
// camera direction when its empty neighbours cancel out), averaged over the
// 3x3 pixels whose visible voxels lie within 2 voxels in depth of the centre's
// (so silhouettes do not blend with what is behind them).
// Lighting: L = normalize(-f + 0.5 up - 0.35 right), f the viewing direction
// (light from the viewer's upper left); shade = (0.2 + 0.8 max(0, n.L)) *
// (1 - 0.2 t), t in [0, 1] the depth between the nearest (0) and the farthest
// (1) visible voxel of the image.
// `threads` 0 = all cores; the result does not depend on it. Throws
// Error(invalid_argument) for an axis outside 0..2 and Error(limit_exceeded)
// for an image over INT_MAX pixels.
// With max_side > 0 the image is shrink_preview(render_preview(...),
// shrink_factor(width, height, max_side)) exactly, but made directly: only
// the blocks' chosen pixels are smoothed and lit, and only the raw normals
// their smoothing takes in are computed (at 8192^3 under a tenth of them),
// and the full-size shades and normals are never held.
PreviewImage render_preview(const BitVolume& volume, View view, int threads = 0, int max_side = 0);

// render_preview() of a volume that arrives slab by slab in z order (a stored
// result replayed from its RLE), in two passes over the slabs: find() every
// slab (the visible voxel of each pixel: along z from the layers where runs
// begin and end, so the cost is the boundaries, not the voxels), then shade()
// every slab again (the normals of the pixels whose visible voxel lies in it,
// with the last two layers of the slab before kept for the neighbours across
// the seam), then take(). The image is exactly render_preview()'s, which is
// the one-slab case. Memory is the image's per-pixel arrays (shrunk by
// max_side: a depth a pixel, 4 bytes, and the blocks'), one layer of bits
// and two more in the second pass.
// Slabs of runs (a stored RLE read as runs, voxd/run_slab.h) give the same
// image at the cost of the runs, not of the grid's bits: the first pass
// walks where runs begin and end, the second reads each visible voxel's 26
// neighbours from 9 rows' runs. A pass takes all its slabs one way.
class PreviewRenderer {
 public:
  // Throws like render_preview() for a bad axis or an image too large;
  // max_side as render_preview()'s.
  PreviewRenderer(const Grid& grid, View view, int threads = 0, int max_side = 0);
  ~PreviewRenderer();
  PreviewRenderer(const PreviewRenderer&) = delete;
  PreviewRenderer& operator=(const PreviewRenderer&) = delete;

  // Layers [k0, k0 + slab.grid().dims.z), right after the previous slab's:
  // first every slab to find(), then every slab to shade(). Throw
  // std::logic_error out of order.
  void find(std::int64_t k0, const BitVolume& slab);
  void shade(std::int64_t k0, const BitVolume& slab);
  void find(std::int64_t k0, const RunSlab& slab);
  void shade(std::int64_t k0, const RunSlab& slab);
  // After both passes. Throws std::logic_error if layers are missing.
  PreviewImage take();

 private:
  struct State;
  std::unique_ptr<State> state_;
};

// How many rendered pixels a side of a shown pixel spans so that an image of
// width x height fits in max_side x max_side: the smallest integer that
// does, 1 when it already fits or max_side is 0 (full size).
int shrink_factor(int width, int height, int max_side);

// The preview `factor` times smaller along each side (rounded up): each
// pixel stands for a block of factor x factor rendered ones and shows the
// block's nearest visible voxel (the nearest to the camera; ties: the first
// in row order) with its shade and normal, so a wall thinner than a block
// stays in view however far the image shrinks, and a pixel is background
// only where its whole block is. Factor 1 returns the image as it is.
// Throws Error(invalid_argument) for a factor below 1.
PreviewImage shrink_preview(const PreviewImage& image, const Grid& grid, View view, int factor);

}  // namespace voxd
