#pragma once
// A configurable PLY writer for decoder tests: every encoding, coordinate and
// index type, property order and extra data a real exporter might produce.
#include <cstdint>
#include <string>
#include <vector>

#include "voxd/mesh.h"

namespace voxd::test {

struct PlyOptions {
  enum class Encoding { ascii, binary_little_endian, binary_big_endian };
  Encoding encoding = Encoding::ascii;
  std::string coordinate_type = "float";  // float, double, or an integer type
  std::string count_type = "uchar";       // type of the face list length
  std::string index_type = "int";         // type of the face list items
  std::string index_name = "vertex_indices";
  // Adds a uchar property before x, a float after y and a list in each face,
  // plus an element the decoder must skip.
  bool extra_properties = false;
  // Writes each pair of consecutive triangles (a,b,c),(a,c,d) as one quad.
  bool quads = false;
};

std::vector<std::uint8_t> to_ply(const Mesh& mesh, const PlyOptions& options);

}  // namespace voxd::test
