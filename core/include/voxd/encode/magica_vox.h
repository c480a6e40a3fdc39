#pragma once
// MagicaVoxel .vox (version 150, with the scene graph extension) from a
// colour volume: voxels with alpha >= 1 are written, alpha 0 ones are empty.
//
// Models. A .vox model is at most 256 voxels along each axis, with byte
// coordinates. The grid is cut into blocks: block (bx, by, bz) covers the
// voxels [256 bx, 256 bx + 256) x [256 by, ...) x [256 bz, ...), clipped to
// the dims; each block with a filled voxel becomes one model (SIZE = the
// block's clipped extent, XYZI = its voxels relative to the block corner, x
// fastest, then y, then z), in block order (bx fastest, then by, then bz).
//
// Placement. The scene is root nTRN (node 0) -> nGRP (node 1) -> per model
// m an nTRN (node 2 + 2m, layer 0) -> nSHP (node 3 + 2m, model m), with one
// LAYR chunk for layer 0. MagicaVoxel anchors a model's translation `_t` at
// its centre: local voxel v of a model of size s lands at _t + v - floor(s/2)
// (integer division), so each model's _t is its block corner + floor(s / 2)
// and voxd voxel (i, j, k) lands at MagicaVoxel position (i, j, k). Both are
// z-up, so the axes map directly. voxel_size and origin have no place in the
// format and are not written.
//
// Palette. Filled voxels take palette indices 1..255; the RGBA chunk holds
// index i's colour at position i - 1 (unused positions are 0, 0, 0, 0). When
// the filled voxels have at most 255 distinct colours (r, g, b, a all
// compared), the palette is exactly those colours, in order of first
// appearance in x-fastest, then y, then z order. Otherwise the colours are
// quantized to 255 by median cut:
//  1. a histogram of the filled voxels over cells of 8 x 8 x 8 x 8 levels of
//     r, g, b, a (5 bits each), each cell with its voxel count and the mean
//     of its voxels' exact colours;
//  2. starting from one box holding every cell, the box with the largest
//     count-weighted sum of squared deviations of its cells' means from the
//     box mean is split, across the channel with the largest such sum, at
//     the count-weighted median (cells ordered by that channel's mean, ties
//     by cell), until there are 255 boxes or no box has two cells;
//  3. each box's palette colour is the count-weighted mean of its voxels'
//     colours, rounded;
//  4. each voxel takes the palette colour nearest its own (squared Euclidean
//     distance over r, g, b, a; ties go to the lower index).
// Every step is a pure function of the volume, so the output is too.
//
// An empty volume (no filled voxel, or dims with a zero) is written as one
// 1 x 1 x 1 model with no voxels at the origin: MagicaVoxel refuses a file
// without a model, and an empty model is the truthful content.
#include "voxd/byte_sink.h"
#include "voxd/dense_volume.h"

namespace voxd {

// Throws Error(invalid_argument) when the volume's values do not match its
// grid (negative dims, or values().size() != voxel_count()), and
// Error(limit_exceeded) when the file would exceed 2^31 - 1 bytes (chunk
// sizes are signed 32-bit; about 530 million filled voxels), checked before
// anything is written.
void write_vox(const DenseVolume<Rgba8>& volume, ByteSink& sink);

}  // namespace voxd
