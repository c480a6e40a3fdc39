#pragma once
// A colour volume as a stack of images: one 8-bit RGBA PNG per z layer, for
// tools that take image sequences (slicers, image editors, ImageJ/Fiji).
//
// Layer k is the voxels with z index k, seen from +z with y up: the image is
// dims.x pixels wide and dims.y high, column i is voxel x index i, and row r
// (row 0 is the top of the image) is voxel y index dims.y - 1 - r, so the
// highest y is the first row ("y descending"). A pixel is the voxel's
// r, g, b, a as stored: alpha 0 (empty) is transparent.
//
// The ZIP (voxd/encode/zip_archive.h) holds, in this order:
//  - manifest.json (deflated): {"layers": dims.z, "width": dims.x,
//    "height": dims.y, "voxel_size": s, "origin": [x, y, z], "axis": "z",
//    "row_order": "y descending"}, origin being the grid's minimum corner
//    (voxd/grid.h), so layer k spans z in origin.z + [k, k + 1] * s;
//  - layer-00000.png, layer-00001.png, ...: layer k, k zero-padded to 5
//    digits (dims are at most 65536, so names sort in layer order), stored
//    uncompressed in the ZIP since PNG is compressed already.
// Each PNG also carries tEXt "voxd:axis" = "z", "voxd:layer" = k and
// "voxd:voxel_size" = s, so a layer on its own still says where it is.
#include <cstdint>
#include <string>

#include "voxd/byte_sink.h"
#include "voxd/dense_volume.h"

namespace voxd {

// "layer-00042.png" for k = 42.
std::string png_layer_name(std::int64_t k);

// The whole stack as a ZIP. A volume of more than 65534 layers would exceed
// the ZIP's 65535 entries and throws Error(limit_exceeded); one without
// voxels, or with a non-finite origin or voxel size, Error(invalid_argument).
void write_png_stack_zip(const DenseVolume<Rgba8>& volume, ByteSink& sink);

// Layer k alone, as the PNG the ZIP holds (e.g. served by URL). Throws
// Error(invalid_argument) when k is not in [0, dims.z) or the volume has no
// voxels.
void write_png_layer(const DenseVolume<Rgba8>& volume, std::int64_t k, ByteSink& sink);

}  // namespace voxd
