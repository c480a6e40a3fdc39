#pragma once
// The part's own mesh with its thickness on each vertex (voxd/analysis/
// surface_thickness.h), as the files a viewer opens:
//  - PLY (binary little-endian): x y z, a float `thickness` and the colour
//    (uchar red green blue) of each vertex, and the triangles. MeshLab,
//    CloudCompare and ParaView colour by either.
//  - glTF 2.0 binary (.glb): POSITION, NORMAL, COLOR_0 (the colours, linear
//    as glTF's colours are, so a viewer shows the ramp's sRGB) and the
//    value as the custom attribute _THICKNESS; under one root node that
//    stands CAD's Z-up model up in glTF's Y-up (the palette glb's, voxd/
//    encode/palette_export.h). Passes the Khronos glTF validator.
// Colours are the thickness images' ramp (voxd/encode/colour_map.h) from
// `low` (its first entry) to `high` (its last), clamped; a vertex that
// reads 0 (no filled voxel under it) takes kNoMaterialColour.
#include <span>
#include <string>

#include "voxd/byte_sink.h"
#include "voxd/encode/colour_map.h"
#include "voxd/mesh.h"

namespace voxd {

struct ThicknessColours {
  float low = 0, high = 1;  // the ramp's ends, in the values' unit
  Rgb colour(float thickness) const;
};

// `mesh`: welded; `thickness`: one value per vertex; `unit`: the values'
// unit, in the files' comments ("model units" or "voxels").
void write_thickness_ply(const Mesh& mesh, std::span<const float> thickness, const ThicknessColours& colours,
                         const std::string& unit, ByteSink& sink);
void write_thickness_glb(const Mesh& mesh, std::span<const float> thickness, const ThicknessColours& colours,
                         const std::string& unit, ByteSink& sink);

}  // namespace voxd
