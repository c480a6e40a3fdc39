// ASCII STL: "solid name", then facets of the form
//   facet normal nx ny nz / outer loop / vertex x y z (x3) / endloop / endfacet
// and "endsolid name". Keywords are matched case-insensitively and tokens may
// be spread over lines in any way, as exporters differ; several solids in one
// file are concatenated. Decoded as triangle soup, like binary STL.
#include <string>

#include "mesh_io/decode_checks.h"
#include "mesh_io/format_decoders.h"
#include "mesh_io/text_lines.h"
#include "voxd/error.h"

namespace voxd::mesh_io {
namespace {

constexpr std::string_view kFormat = "ASCII STL";

// Tokens of the whole file, across line breaks.
class TokenStream {
 public:
  explicit TokenStream(std::string_view text) : lines_(text) {}

  // Empty at the end of the text.
  std::string_view next() {
    for (;;) {
      const std::string_view token = lines_.next_token();
      if (!token.empty()) return token;
      if (!lines_.next_line()) return {};
    }
  }
  void skip_rest_of_line() { lines_.skip_rest_of_line(); }
  std::size_t line() const { return lines_.line_number(); }

 private:
  TextLines lines_;
};

class AsciiStlParser {
 public:
  AsciiStlParser(std::string_view text, const DecodeLimits& limits) : tokens_(text), limits_(limits) {}

  Mesh parse() {
    const std::string_view first = tokens_.next();
    if (!equals_ignoring_case(first, "solid")) fail_expected("'solid'", first);
    tokens_.skip_rest_of_line();  // the solid's name, which may contain anything
    for (;;) {
      const std::string_view token = tokens_.next();
      if (token.empty()) break;  // a missing "endsolid" is common and harmless
      if (equals_ignoring_case(token, "facet")) {
        parse_facet();
      } else if (equals_ignoring_case(token, "endsolid")) {
        tokens_.skip_rest_of_line();
        const std::string_view next = tokens_.next();
        if (next.empty()) break;
        if (!equals_ignoring_case(next, "solid")) fail_expected("'solid' or the end of the file after 'endsolid'", next);
        tokens_.skip_rest_of_line();
      } else {
        fail_expected("'facet' or 'endsolid'", token);
      }
    }
    if (mesh_.triangles.empty())
      throw Error(ErrorCode::no_usable_triangles, "ASCII STL contains no facets; the solid is empty");
    return std::move(mesh_);
  }

 private:
  void parse_facet() {
    facet_line_ = tokens_.line();
    // The normal is optional in practice and recomputed by anyone who needs
    // it, so whatever stands between "facet" and "outer" is skipped (bounded,
    // so a missing "outer" is reported near where it belongs).
    std::string_view token = next_in_facet();
    for (int skipped = 0; !equals_ignoring_case(token, "outer"); ++skipped) {
      if (skipped == 4) fail_expected("'outer loop'", token);
      token = next_in_facet();
    }
    expect("loop");
    check_triangle_limit(mesh_.triangles.size() + 1, limits_, kFormat);
    const auto first = static_cast<std::uint32_t>(mesh_.vertices.size());
    for (int corner = 0; corner < 3; ++corner) {
      token = next_in_facet();
      if (!equals_ignoring_case(token, "vertex")) {
        if (equals_ignoring_case(token, "endloop"))
          fail("the facet starting at line " + std::to_string(facet_line_) + " has " + std::to_string(corner) +
               " vertices; a facet needs exactly 3");
        fail_expected("'vertex'", token);
      }
      mesh_.vertices.push_back(parse_vertex());
    }
    token = next_in_facet();
    if (equals_ignoring_case(token, "vertex"))
      fail("the facet starting at line " + std::to_string(facet_line_) +
           " has more than 3 vertices; STL facets are triangles, triangulate the mesh before export");
    if (!equals_ignoring_case(token, "endloop")) fail_expected("'endloop'", token);
    expect("endfacet");
    mesh_.triangles.push_back({first, first + 1, first + 2});
  }

  glm::vec3 parse_vertex() {
    glm::vec3 v;
    for (int axis = 0; axis < 3; ++axis) {
      const std::string_view token = next_in_facet();
      if (!parse_float(token, v[axis]))
        fail("expected 3 numbers after 'vertex', found " + quote_token(token) + " as coordinate " +
             std::string(1, "xyz"[axis]));
    }
    if (!is_finite(v)) throw_non_finite(kFormat, "the vertex at line " + std::to_string(tokens_.line()));
    return v;
  }

  std::string_view next_in_facet() {
    const std::string_view token = tokens_.next();
    if (token.empty())
      throw Error(ErrorCode::truncated_input, "ASCII STL ends inside the facet starting at line " +
                                                  std::to_string(facet_line_) + "; the file is cut off");
    return token;
  }

  void expect(std::string_view keyword) {
    const std::string_view token = next_in_facet();
    if (!equals_ignoring_case(token, keyword)) fail_expected(quote_token(keyword), token);
  }

  [[noreturn]] void fail_expected(const std::string& expected, std::string_view found) {
    fail("expected " + expected + ", found " + (found.empty() ? std::string("the end of the file") : quote_token(found)));
  }

  [[noreturn]] void fail(const std::string& what) {
    throw Error(ErrorCode::malformed_input, "ASCII STL, line " + std::to_string(tokens_.line()) + ": " + what);
  }

  TokenStream tokens_;
  const DecodeLimits& limits_;
  Mesh mesh_;
  std::size_t facet_line_ = 0;
};

}  // namespace

Mesh decode_stl_ascii(std::string_view text, const DecodeLimits& limits) {
  return AsciiStlParser(text, limits).parse();
}

}  // namespace voxd::mesh_io
