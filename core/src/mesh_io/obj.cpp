// Wavefront OBJ: only geometry is read, "v x y z" and "f a b c ..." lines;
// texture coordinates, normals, groups and materials are ignored. Faces are
// polygons, fan-triangulated; an index is 1-based, or negative to count back
// from the last vertex defined so far, and may carry /vt/vn parts.
#include <limits>
#include <string>

#include "mesh_io/decode_checks.h"
#include "mesh_io/format_decoders.h"
#include "mesh_io/text_lines.h"
#include "voxd/error.h"

namespace voxd::mesh_io {
namespace {

constexpr std::string_view kFormat = "OBJ";

class ObjParser {
 public:
  ObjParser(std::string_view text, const DecodeLimits& limits) : lines_(text), limits_(limits) {}

  Mesh parse() {
    while (lines_.next_line()) {
      const std::string_view keyword = lines_.next_token();
      if (keyword == "v") {
        parse_vertex();
      } else if (keyword == "f") {
        parse_face();
      }
      // Anything else (comments, vt, vn, g, o, s, usemtl, mtllib, l, ...) does
      // not describe triangles.
    }
    // Positive indices may point forward, so they are checked once all
    // vertices are known.
    if (largest_index_ > mesh_.vertices.size())
      throw Error(ErrorCode::malformed_input,
                  "OBJ, line " + std::to_string(largest_index_line_) + ": face refers to vertex " +
                      std::to_string(largest_index_) + " but the file defines only " +
                      std::to_string(mesh_.vertices.size()) + " vertices");
    keep_usable_triangles(mesh_, kFormat);
    return std::move(mesh_);
  }

 private:
  void parse_vertex() {
    glm::vec3 v;
    for (int axis = 0; axis < 3; ++axis) {
      const std::string_view token = lines_.next_token();
      if (!parse_float(token, v[axis]))
        fail("a vertex needs 3 numbers, found " + (token.empty() ? std::string("nothing") : quote_token(token)) +
             " as coordinate " + std::string(1, "xyz"[axis]));
    }
    // A fourth number (w) or vertex colours may follow; neither shapes the mesh.
    if (!is_finite(v)) throw_non_finite(kFormat, "the vertex at line " + std::to_string(lines_.line_number()));
    if (mesh_.vertices.size() == std::numeric_limits<std::uint32_t>::max())
      throw Error(ErrorCode::limit_exceeded, "OBJ has more than 4294967295 vertices");
    mesh_.vertices.push_back(v);
  }

  void parse_face() {
    std::uint32_t first = 0, previous = 0;
    int corners = 0;
    for (std::string_view token = lines_.next_token(); !token.empty(); token = lines_.next_token()) {
      const std::uint32_t index = parse_index(token);
      if (corners >= 2) {
        check_triangle_limit(mesh_.triangles.size() + 1, limits_, kFormat);
        mesh_.triangles.push_back({first, previous, index});
      }
      if (corners == 0) first = index;
      previous = index;
      ++corners;
    }
    if (corners < 3)
      fail("a face needs at least 3 vertices, this one has " + std::to_string(corners));
  }

  // Returns the 0-based vertex index of "i", "i/t", "i//n" or "i/t/n".
  std::uint32_t parse_index(std::string_view token) {
    const std::string_view vertex_part = token.substr(0, token.find('/'));
    std::int64_t index = 0;
    if (!parse_integer(vertex_part, index))
      fail("face vertex " + quote_token(token) + " does not start with a vertex number");
    const auto defined = static_cast<std::int64_t>(mesh_.vertices.size());
    if (index < 0) {
      // Compared as index < -defined: negating the index itself overflows
      // for INT64_MIN.
      if (index < -defined)
        fail("face refers to vertex " + std::to_string(index) + " (counting back) but only " +
             std::to_string(defined) + " vertices are defined before it");
      return static_cast<std::uint32_t>(defined + index);
    }
    if (index == 0) fail("face refers to vertex 0; OBJ vertex numbers start at 1");
    if (index > static_cast<std::int64_t>(std::numeric_limits<std::uint32_t>::max()))
      fail("face refers to vertex " + std::to_string(index) + ", beyond any vertex the file can define");
    if (static_cast<std::uint64_t>(index) > largest_index_) {
      largest_index_ = static_cast<std::uint64_t>(index);
      largest_index_line_ = lines_.line_number();
    }
    return static_cast<std::uint32_t>(index - 1);
  }

  [[noreturn]] void fail(const std::string& what) {
    throw Error(ErrorCode::malformed_input, "OBJ, line " + std::to_string(lines_.line_number()) + ": " + what);
  }

  TextLines lines_;
  const DecodeLimits& limits_;
  Mesh mesh_;
  std::uint64_t largest_index_ = 0;  // 1-based, the largest positive index seen
  std::size_t largest_index_line_ = 0;
};

}  // namespace

Mesh decode_obj(std::string_view text, const DecodeLimits& limits) { return ObjParser(text, limits).parse(); }

}  // namespace voxd::mesh_io
