#pragma once
// A triangle mesh as the files other tools open, in its own coordinates
// (model units): binary STL (a triangle soup: readers that weld by position
// join what voxd/encode/volume_surface.h keeps apart), binary little-endian
// PLY and glTF 2.0 binary (indexed: the topology is kept). The glb stands
// CAD's Z-up model up in glTF's Y-up under one root node (as the palette
// and thickness glb files do) and passes the Khronos glTF validator.
#include <string>

#include "voxd/byte_sink.h"
#include "voxd/mesh.h"

namespace voxd {

void write_mesh_stl(const Mesh& mesh, const std::string& description, ByteSink& sink);
void write_mesh_ply(const Mesh& mesh, const std::string& description, ByteSink& sink);
void write_mesh_glb(const Mesh& mesh, const std::string& description, ByteSink& sink);

}  // namespace voxd
