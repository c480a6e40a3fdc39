// PLY (ascii, binary_little_endian, binary_big_endian). The header declares
// elements and their properties; voxd reads x, y, z of "vertex" (any numeric
// type, any position among other properties) and the "vertex_indices" (or
// "vertex_index") list of "face", fan-triangulating polygons. Every other
// element and property is skipped.
//
// Header counts are untrusted: before anything is allocated, the counts are
// checked against the bytes that follow the header, so a 100-byte file that
// claims billions of vertices fails at once.
#include <algorithm>
#include <bit>
#include <cstring>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "mesh_io/decode_checks.h"
#include "mesh_io/format_decoders.h"
#include "mesh_io/text_lines.h"
#include "voxd/error.h"

namespace voxd::mesh_io {
namespace {

constexpr std::string_view kFormat = "PLY";

enum class PlyType : std::uint8_t { int8, uint8, int16, uint16, int32, uint32, float32, float64 };

std::optional<PlyType> parse_type(std::string_view name) {
  struct Alias {
    std::string_view name;
    PlyType type;
  };
  static constexpr Alias aliases[] = {
      {"char", PlyType::int8},     {"int8", PlyType::int8},       {"uchar", PlyType::uint8},
      {"uint8", PlyType::uint8},   {"short", PlyType::int16},     {"int16", PlyType::int16},
      {"ushort", PlyType::uint16}, {"uint16", PlyType::uint16},   {"int", PlyType::int32},
      {"int32", PlyType::int32},   {"uint", PlyType::uint32},     {"uint32", PlyType::uint32},
      {"float", PlyType::float32}, {"float32", PlyType::float32}, {"double", PlyType::float64},
      {"float64", PlyType::float64}};
  for (const Alias& a : aliases)
    if (a.name == name) return a.type;
  return std::nullopt;
}

std::size_t size_of(PlyType type) {
  switch (type) {
    case PlyType::int8:
    case PlyType::uint8: return 1;
    case PlyType::int16:
    case PlyType::uint16: return 2;
    case PlyType::int32:
    case PlyType::uint32:
    case PlyType::float32: return 4;
    case PlyType::float64: return 8;
  }
  return 1;
}

bool is_integer(PlyType type) { return type != PlyType::float32 && type != PlyType::float64; }

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::float32;  // of the items, for a list
  bool is_list = false;
  PlyType count_type = PlyType::uint8;
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;
};

enum class PlyEncoding { ascii, binary_little_endian, binary_big_endian };

struct PlyHeader {
  PlyEncoding encoding = PlyEncoding::ascii;
  std::vector<PlyElement> elements;
};

// What the caller of a data source is reading, for error messages.
struct ReadingAt {
  const std::string* element = nullptr;
  std::uint64_t index = 0;
  std::uint64_t count = 0;

  std::string describe() const {
    return *element + " " + std::to_string(index) + " of " + std::to_string(count);
  }
};

// Binary data after the header, bounds-checked on every read.
class BinarySource {
 public:
  BinarySource(std::span<const std::uint8_t> data, std::size_t offset, bool big_endian)
      : data_(data), pos_(offset), big_endian_(big_endian) {}

  std::int64_t read_integer(PlyType type) {
    switch (type) {
      case PlyType::int8: return read<std::int8_t>();
      case PlyType::uint8: return read<std::uint8_t>();
      case PlyType::int16: return read<std::int16_t>();
      case PlyType::uint16: return read<std::uint16_t>();
      case PlyType::int32: return read<std::int32_t>();
      case PlyType::uint32: return read<std::uint32_t>();
      case PlyType::float32:
      case PlyType::float64: break;  // the header check keeps float lists out
    }
    return 0;
  }

  float read_coordinate(PlyType type) {
    switch (type) {
      case PlyType::float32: return read<float>();
      case PlyType::float64: return detail::narrow_to_float(read<double>());
      default: return static_cast<float>(read_integer(type));
    }
  }

  void skip(PlyType type, std::uint64_t count) {
    const std::uint64_t bytes_per_item = size_of(type);
    if (count > (data_.size() - pos_) / bytes_per_item) throw_truncated();
    pos_ += static_cast<std::size_t>(count * bytes_per_item);
  }

  std::string where() const { return "byte offset " + std::to_string(pos_); }
  ReadingAt at;

 private:
  template <typename T>
  T read() {
    if (data_.size() - pos_ < sizeof(T)) throw_truncated();
    using Bits = std::conditional_t<sizeof(T) == 1, std::uint8_t,
                                    std::conditional_t<sizeof(T) == 2, std::uint16_t,
                                                       std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint64_t>>>;
    Bits bits;
    std::memcpy(&bits, data_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    if (big_endian_ != (std::endian::native == std::endian::big)) bits = byteswap(bits);
    return std::bit_cast<T>(bits);
  }

  template <typename Bits>
  static Bits byteswap(Bits bits) {
    if constexpr (sizeof(Bits) == 1) return bits;
    if constexpr (sizeof(Bits) == 2) return __builtin_bswap16(bits);
    if constexpr (sizeof(Bits) == 4) return __builtin_bswap32(bits);
    if constexpr (sizeof(Bits) == 8) return __builtin_bswap64(bits);
  }

  [[noreturn]] void throw_truncated() const {
    throw Error(ErrorCode::truncated_input, "PLY data ends at byte offset " + std::to_string(data_.size()) +
                                                ", inside " + at.describe() + "; the file is cut off");
  }

  std::span<const std::uint8_t> data_;
  std::size_t pos_;
  bool big_endian_;
};

// ASCII data after the header: whitespace-separated numbers, conventionally
// one element per line, though line breaks are not relied upon.
class AsciiSource {
 public:
  explicit AsciiSource(TextLines& lines) : lines_(lines) {}

  std::int64_t read_integer(PlyType /*type*/) {
    const std::string_view token = next();
    std::int64_t value = 0;
    if (!parse_integer(token, value)) fail("expected an integer, found " + quote_token(token));
    return value;
  }

  float read_coordinate(PlyType type) {
    const std::string_view token = next();
    float value = 0.0f;
    bool ok = false;
    if (type == PlyType::float32) {
      ok = parse_float(token, value);
    } else if (type == PlyType::float64) {
      ok = parse_double_as_float(token, value);
    } else {
      std::int64_t integer = 0;
      ok = parse_integer(token, integer);
      value = static_cast<float>(integer);
    }
    if (!ok) fail("expected a number, found " + quote_token(token));
    return value;
  }

  void skip(PlyType /*type*/, std::uint64_t count) {
    for (std::uint64_t i = 0; i < count; ++i) next();
  }

  std::string where() const { return "line " + std::to_string(lines_.line_number()); }
  ReadingAt at;

 private:
  std::string_view next() {
    for (;;) {
      const std::string_view token = lines_.next_token();
      if (!token.empty()) return token;
      if (!lines_.next_line())
        throw Error(ErrorCode::truncated_input, "PLY data ends at line " + std::to_string(lines_.line_number()) +
                                                    ", inside " + at.describe() + "; the file is cut off");
    }
  }

  [[noreturn]] void fail(const std::string& what) const {
    throw Error(ErrorCode::malformed_input, "PLY, line " + std::to_string(lines_.line_number()) + " (" +
                                                at.describe() + "): " + what);
  }

  TextLines& lines_;
};

class PlyParser {
 public:
  PlyParser(std::span<const std::uint8_t> data, const DecodeLimits& limits, DecodeWarnings* warnings)
      : data_(data),
        lines_(std::string_view(reinterpret_cast<const char*>(data.data()), data.size())),
        limits_(limits),
        warnings_(warnings) {}

  Mesh parse() {
    parse_header();
    find_vertex_and_face_elements();
    check_counts_against_data();
    if (header_.encoding == PlyEncoding::ascii) {
      AsciiSource source(lines_);
      read_elements(source);
    } else {
      BinarySource source(data_, lines_.next_line_offset(), header_.encoding == PlyEncoding::binary_big_endian);
      read_elements(source);
    }
    keep_usable_triangles(mesh_, kFormat);
    return std::move(mesh_);
  }

 private:
  // ---- header ---------------------------------------------------------------

  void parse_header() {
    if (!lines_.next_line() || lines_.next_token() != "ply") header_error("the file must start with 'ply'");
    bool has_format = false;
    for (;;) {
      if (!lines_.next_line())
        throw Error(ErrorCode::malformed_input, "PLY header never ends: there is no 'end_header' line");
      const std::string_view keyword = lines_.next_token();
      if (keyword == "end_header") {
        lines_.skip_rest_of_line();  // ASCII data starts on the next line
        break;
      }
      if (keyword.empty() || keyword == "comment" || keyword == "obj_info") continue;
      if (keyword == "format") {
        const std::string_view encoding = lines_.next_token();
        if (encoding == "ascii") header_.encoding = PlyEncoding::ascii;
        else if (encoding == "binary_little_endian") header_.encoding = PlyEncoding::binary_little_endian;
        else if (encoding == "binary_big_endian") header_.encoding = PlyEncoding::binary_big_endian;
        else header_error("unknown format " + quote_token(encoding) +
                          "; expected ascii, binary_little_endian or binary_big_endian");
        has_format = true;
      } else if (keyword == "element") {
        parse_element_line();
      } else if (keyword == "property") {
        parse_property_line();
      } else {
        // Blender 2.4x wrote its name on a line of its own ("Created by
        // Blender3D 247 ..."), which assimp and MeshLab read past: a line
        // of no known keyword says nothing of the data's layout, so it is
        // read as a comment, and said.
        if (warnings_)
          warnings_->push_back("PLY header, line " + std::to_string(lines_.line_number()) + ": unknown keyword " +
                               quote_token(keyword) + " read as a comment; a PLY header line starts with ply, format, " +
                               "element, property, comment, obj_info or end_header");
        lines_.skip_rest_of_line();
      }
    }
    if (!has_format) header_error("the header has no 'format' line");
  }

  void parse_element_line() {
    PlyElement element;
    element.name = std::string(lines_.next_token());
    const std::string_view count = lines_.next_token();
    std::int64_t value = -1;
    if (element.name.empty() || !parse_integer(count, value) || value < 0)
      header_error("expected 'element <name> <count>' with a non-negative count");
    element.count = static_cast<std::uint64_t>(value);
    header_.elements.push_back(std::move(element));
  }

  void parse_property_line() {
    if (header_.elements.empty()) header_error("'property' before any 'element'");
    PlyProperty property;
    std::string_view type_name = lines_.next_token();
    if (type_name == "list") {
      property.is_list = true;
      const std::string_view count_type_name = lines_.next_token();
      const auto count_type = parse_type(count_type_name);
      if (!count_type || !is_integer(*count_type))
        header_error("list count type " + quote_token(count_type_name) + " is not an integer type");
      property.count_type = *count_type;
      type_name = lines_.next_token();
    }
    const auto type = parse_type(type_name);
    if (!type) header_error("unknown property type " + quote_token(type_name));
    property.type = *type;
    property.name = std::string(lines_.next_token());
    if (property.name.empty()) header_error("property has no name");
    header_.elements.back().properties.push_back(std::move(property));
  }

  void find_vertex_and_face_elements() {
    for (std::size_t e = 0; e < header_.elements.size(); ++e) {
      const std::string& name = header_.elements[e].name;
      std::optional<std::size_t>* slot = name == "vertex" ? &vertex_element_
                                         : name == "face"   ? &face_element_
                                                            : nullptr;
      if (!slot) continue;
      if (*slot) throw Error(ErrorCode::malformed_input, "PLY header declares the element '" + name + "' twice");
      *slot = e;
    }
    if (!vertex_element_)
      throw Error(ErrorCode::malformed_input, "PLY header declares no 'vertex' element, so there is no geometry");
    const PlyElement& vertex = header_.elements[*vertex_element_];
    for (int axis = 0; axis < 3; ++axis) {
      const std::string name(1, "xyz"[axis]);
      const auto it = std::find_if(vertex.properties.begin(), vertex.properties.end(),
                                   [&](const PlyProperty& p) { return p.name == name; });
      if (it == vertex.properties.end())
        throw Error(ErrorCode::malformed_input, "PLY vertex element has no '" + name + "' property");
      if (it->is_list)
        throw Error(ErrorCode::malformed_input, "PLY vertex property '" + name + "' is a list; expected a number");
      coordinate_property_[axis] = static_cast<std::size_t>(it - vertex.properties.begin());
    }
    if (vertex.count > std::numeric_limits<std::uint32_t>::max())
      throw Error(ErrorCode::limit_exceeded, "PLY declares " + std::to_string(vertex.count) +
                                                 " vertices; voxd supports at most 4294967295");
    if (!face_element_) return;  // a point cloud: reported as having no faces
    const PlyElement& face = header_.elements[*face_element_];
    const auto it = std::find_if(face.properties.begin(), face.properties.end(), [](const PlyProperty& p) {
      return p.name == "vertex_indices" || p.name == "vertex_index";
    });
    if (it == face.properties.end())
      throw Error(ErrorCode::malformed_input,
                  "PLY face element has no 'vertex_indices' (or 'vertex_index') property");
    if (!it->is_list || !is_integer(it->type))
      throw Error(ErrorCode::malformed_input,
                  "PLY face property '" + it->name + "' must be a list of integers, e.g. 'property list uchar int " +
                      it->name + "'");
    index_property_ = static_cast<std::size_t>(it - face.properties.begin());
    // Every face gives at least one triangle (smaller ones are rejected).
    check_triangle_limit(face.count, limits_, kFormat);
  }

  // Each element needs some minimum of data (fixed-size properties, list
  // counts, three indices per face); their sum must fit in what follows the
  // header, which bounds every allocation made from the counts.
  void check_counts_against_data() {
    const bool ascii = header_.encoding == PlyEncoding::ascii;
    const std::uint64_t available = data_.size() - lines_.next_line_offset();
    // Counts fit in 63 bits and per-element minima are small, so 128 bits
    // cannot overflow.
    unsigned __int128 needed = 0;
    std::string declared;
    for (std::size_t e = 0; e < header_.elements.size(); ++e) {
      const PlyElement& element = header_.elements[e];
      std::uint64_t per_element = 0;  // bytes for binary, tokens for ascii
      for (std::size_t p = 0; p < element.properties.size(); ++p) {
        const PlyProperty& property = element.properties[p];
        const bool face_indices = face_element_ == e && index_property_ == p;
        const std::uint64_t items = face_indices ? 3 : 0;
        if (ascii) per_element += property.is_list ? 1 + items : 1;
        else per_element += property.is_list ? size_of(property.count_type) + items * size_of(property.type)
                                             : size_of(property.type);
      }
      needed += static_cast<unsigned __int128>(element.count) * per_element;
      declared += (declared.empty() ? "" : ", ") + std::to_string(element.count) + " " + element.name;
    }
    // ASCII tokens need a separator between them.
    if (ascii && needed > 0) needed = 2 * needed - 1;
    if (needed <= available) return;
    const std::string bound = needed > std::numeric_limits<std::uint64_t>::max()
                                  ? std::string("more than 2^64")
                                  : std::to_string(static_cast<std::uint64_t>(needed));
    throw Error(ErrorCode::truncated_input,
                "PLY header declares " + declared + " elements, which need at least " + bound +
                    " bytes of data, but only " + std::to_string(available) +
                    " bytes follow the header; the file is cut off or its header is wrong");
  }

  // ---- data -----------------------------------------------------------------

  template <typename Source>
  void read_elements(Source& source) {
    for (std::size_t e = 0; e < header_.elements.size(); ++e) {
      const PlyElement& element = header_.elements[e];
      source.at = {&element.name, 0, element.count};
      if (element.properties.empty()) continue;  // nothing to read, however many
      if (vertex_element_ == e) read_vertices(source, element);
      else if (face_element_ == e) read_faces(source, element);
      else skip_elements(source, element);
    }
  }

  template <typename Source>
  void read_vertices(Source& source, const PlyElement& element) {
    mesh_.vertices.resize(element.count);
    for (std::uint64_t i = 0; i < element.count; ++i) {
      source.at.index = i;
      glm::vec3 v(0.0f);
      for (std::size_t p = 0; p < element.properties.size(); ++p) {
        const PlyProperty& property = element.properties[p];
        if (p == coordinate_property_[0]) v.x = source.read_coordinate(property.type);
        else if (p == coordinate_property_[1]) v.y = source.read_coordinate(property.type);
        else if (p == coordinate_property_[2]) v.z = source.read_coordinate(property.type);
        else skip_property(source, property);
      }
      if (!is_finite(v))
        throw_non_finite(kFormat, "vertex " + std::to_string(i) + " (read up to " + source.where() + ")");
      mesh_.vertices[i] = v;
    }
  }

  template <typename Source>
  void read_faces(Source& source, const PlyElement& element) {
    const std::uint64_t vertex_count = header_.elements[*vertex_element_].count;
    mesh_.triangles.reserve(element.count);
    std::uint64_t triangles = 0;
    for (std::uint64_t i = 0; i < element.count; ++i) {
      source.at.index = i;
      for (std::size_t p = 0; p < element.properties.size(); ++p) {
        const PlyProperty& property = element.properties[p];
        if (p != index_property_) {
          skip_property(source, property);
          continue;
        }
        const std::int64_t corners = source.read_integer(property.count_type);
        if (corners < 3)
          data_error(source, "a face needs at least 3 vertices, this one has " + std::to_string(corners));
        triangles += static_cast<std::uint64_t>(corners - 2);
        check_triangle_limit(triangles, limits_, kFormat);
        auto read_index = [&] {
          const std::int64_t index = source.read_integer(property.type);
          if (index < 0 || static_cast<std::uint64_t>(index) >= vertex_count)
            data_error(source, "face refers to vertex " + std::to_string(index) + " but the file has " +
                                   std::to_string(vertex_count) + " vertices (numbered from 0)");
          return static_cast<std::uint32_t>(index);
        };
        const std::uint32_t first = read_index();
        std::uint32_t previous = read_index();
        for (std::int64_t c = 2; c < corners; ++c) {
          const std::uint32_t current = read_index();
          mesh_.triangles.push_back({first, previous, current});
          previous = current;
        }
      }
    }
  }

  template <typename Source>
  void skip_elements(Source& source, const PlyElement& element) {
    for (std::uint64_t i = 0; i < element.count; ++i) {
      source.at.index = i;
      for (const PlyProperty& property : element.properties) skip_property(source, property);
    }
  }

  template <typename Source>
  void skip_property(Source& source, const PlyProperty& property) {
    if (!property.is_list) {
      source.skip(property.type, 1);
      return;
    }
    const std::int64_t items = source.read_integer(property.count_type);
    if (items < 0) data_error(source, "list '" + property.name + "' has a negative length");
    source.skip(property.type, static_cast<std::uint64_t>(items));
  }

  template <typename Source>
  [[noreturn]] void data_error(const Source& source, const std::string& what) {
    throw Error(ErrorCode::malformed_input, "PLY, " + source.at.describe() + " (" + source.where() + "): " + what);
  }

  [[noreturn]] void header_error(const std::string& what) {
    throw Error(ErrorCode::malformed_input,
                "PLY header, line " + std::to_string(lines_.line_number()) + ": " + what);
  }

  std::span<const std::uint8_t> data_;
  TextLines lines_;
  const DecodeLimits& limits_;
  DecodeWarnings* warnings_;
  PlyHeader header_;
  std::optional<std::size_t> vertex_element_, face_element_;
  std::size_t coordinate_property_[3] = {0, 0, 0};
  std::size_t index_property_ = 0;
  Mesh mesh_;
};

}  // namespace

Mesh decode_ply(std::span<const std::uint8_t> data, const DecodeLimits& limits, DecodeWarnings* warnings) {
  return PlyParser(data, limits, warnings).parse();
}

}  // namespace voxd::mesh_io
