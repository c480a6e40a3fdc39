#pragma once
// Rendering palettes (Cavagnino & Gribaudo 2010): what a front end shows
// for each voxel of a palette voxelization. Each element maps to an ordered
// list of display objects, each with a threshold D on the similarity B of
// the voxel's choice; the voxel shows the first object whose D <= B (so a
// poorly matched wedge can fall back to, say, a plain brick), or nothing.
#include <cstdint>
#include <string>
#include <vector>

#include "voxd/dense_volume.h"
#include "voxd/voxelize/palette.h"

namespace voxd {

struct DisplayChoice {
  std::uint8_t object = 0;     // 1-based index into RenderPalette::objects
  double min_similarity = 0;   // D in [0, 1]
};

struct RenderPalette {
  std::vector<std::string> objects;                 // display object names, at most 255
  std::vector<std::vector<DisplayChoice>> by_element;  // by element index; missing or empty: nothing shown
  bool empty() const { return objects.empty(); }
};

// The display object index per voxel: 0 for nothing, else 1 + the index
// into render.objects. `similarity` holds round(255 B).
DenseVolume<std::uint8_t> render_palette(const DenseVolume<std::uint8_t>& element,
                                         const DenseVolume<std::uint8_t>& similarity, const RenderPalette& render);

}  // namespace voxd
