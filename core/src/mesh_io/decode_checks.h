#pragma once
// Checks shared by the decoders, so every format words the same problem the
// same way.
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>

#include <glm/vec3.hpp>

#include "voxd/mesh.h"
#include "voxd/mesh_io/mesh_decode.h"

namespace voxd::mesh_io {

inline bool is_finite(const glm::vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// Throws limit_exceeded when `triangles` is over the limit. `format` names the
// format in the message ("binary STL").
void check_triangle_limit(std::uint64_t triangles, const DecodeLimits& limits, std::string_view format);

// Throws non_finite_coordinates naming `where` ("line 12", "vertex 7").
[[noreturn]] void throw_non_finite(std::string_view format, std::string_view where);

// Drops triangles that repeat an index (they cover no area and break edge
// topology), then throws no_usable_triangles if nothing is left.
void keep_usable_triangles(Mesh& mesh, std::string_view format);

// A short, printable rendition of untrusted text for error messages.
std::string quote_token(std::string_view token);

}  // namespace voxd::mesh_io
