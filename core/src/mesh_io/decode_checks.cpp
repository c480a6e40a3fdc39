#include "mesh_io/decode_checks.h"

#include <algorithm>

#include "voxd/error.h"

namespace voxd::mesh_io {

void check_triangle_limit(std::uint64_t triangles, const DecodeLimits& limits, std::string_view format) {
  if (triangles <= limits.max_triangles) return;
  throw Error(ErrorCode::limit_exceeded,
              std::string(format) + " has at least " + std::to_string(triangles) + " triangles, over the limit of " +
                  std::to_string(limits.max_triangles) + "; simplify (decimate) the mesh before uploading it");
}

void throw_non_finite(std::string_view format, std::string_view where) {
  throw Error(ErrorCode::non_finite_coordinates,
              std::string(format) + ": " + std::string(where) +
                  " has a coordinate that is NaN, infinite or too large for 32-bit float; "
                  "fix or remove that vertex in the modelling tool and export again");
}

void keep_usable_triangles(Mesh& mesh, std::string_view format) {
  const std::size_t before = mesh.triangles.size();
  std::erase_if(mesh.triangles, [](const std::array<std::uint32_t, 3>& t) {
    return t[0] == t[1] || t[1] == t[2] || t[0] == t[2];
  });
  if (!mesh.triangles.empty()) return;
  if (before == 0)
    throw Error(ErrorCode::no_usable_triangles,
                std::string(format) + " contains no faces (only points or lines?); voxelizing needs a triangle mesh");
  throw Error(ErrorCode::no_usable_triangles,
              std::string(format) + " has " + std::to_string(before) +
                  " faces but every one repeats a vertex index, so none encloses any area");
}

std::string quote_token(std::string_view token) {
  constexpr std::size_t max_shown = 40;
  std::string out = "'";
  for (std::size_t i = 0; i < std::min(token.size(), max_shown); ++i) {
    const auto c = static_cast<unsigned char>(token[i]);
    if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
    } else {
      static constexpr char hex[] = "0123456789abcdef";
      out += "\\x";
      out += hex[c >> 4];
      out += hex[c & 15];
    }
  }
  if (token.size() > max_shown) out += "...";
  return out + "'";
}

}  // namespace voxd::mesh_io
