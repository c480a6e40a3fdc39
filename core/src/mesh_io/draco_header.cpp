#include "mesh_io/draco_header.h"

#include <string>

#include "mesh_io/decode_checks.h"
#include "voxd/error.h"

namespace voxd::mesh_io {
namespace {

constexpr std::uint16_t kMetadataFlag = 0x8000;
constexpr int kMaxMetadataDepth = 32;

[[noreturn]] void cut_off(const char* what) {
  throw Error(ErrorCode::malformed_input,
              std::string("the Draco header is cut off or invalid (") + what + "); the file is corrupt");
}

class HeaderReader {
 public:
  explicit HeaderReader(std::span<const std::uint8_t> data) : data_(data) {}

  std::uint8_t u8(const char* what) {
    if (pos_ >= data_.size()) cut_off(what);
    return data_[pos_++];
  }
  std::uint32_t u32(const char* what) {
    std::uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v |= static_cast<std::uint32_t>(u8(what)) << (8 * i);
    return v;
  }
  std::uint64_t varint(const char* what) {
    std::uint64_t v = 0;
    for (int shift = 0; shift < 35; shift += 7) {  // a varUI32 has at most 5 bytes
      const std::uint8_t b = u8(what);
      v |= static_cast<std::uint64_t>(b & 0x7f) << shift;
      if (!(b & 0x80)) return v;
    }
    cut_off(what);
  }
  void skip(std::uint64_t n, const char* what) {
    if (n > data_.size() - pos_) cut_off(what);
    pos_ += static_cast<std::size_t>(n);
  }

  // A metadata element: entries (key, value), then named sub-elements.
  void metadata_element(int depth) {
    if (depth > kMaxMetadataDepth) cut_off("metadata nested too deep");
    const std::uint64_t entries = varint("metadata entries");
    for (std::uint64_t i = 0; i < entries; ++i) {
      skip(u8("metadata key size"), "metadata key");
      skip(u8("metadata value size"), "metadata value");
    }
    const std::uint64_t children = varint("metadata children");
    for (std::uint64_t i = 0; i < children; ++i) {
      skip(u8("metadata key size"), "metadata key");
      metadata_element(depth + 1);
    }
  }

 private:
  std::span<const std::uint8_t> data_;
  std::size_t pos_ = 0;
};

}  // namespace

DracoClaims read_draco_claims(std::span<const std::uint8_t> data) {
  HeaderReader in(data);
  for (const char c : {'D', 'R', 'A', 'C', 'O'})
    if (in.u8("magic") != static_cast<std::uint8_t>(c)) cut_off("no DRACO magic");
  DracoClaims claims;
  claims.version_major = in.u8("version");
  claims.version_minor = in.u8("version");
  const bool mesh = in.u8("encoder type") == 1;  // else a point cloud, refused by the decoder
  const std::uint8_t method = in.u8("encoder method");
  if (method > 1) cut_off("unknown encoder method");
  claims.edgebreaker = method == 1;
  const std::uint16_t flags = static_cast<std::uint16_t>(in.u8("flags") | in.u8("flags") << 8);
  const int version = claims.version_major * 256 + claims.version_minor;
  const bool current = version >= 2 * 256 + 2;  // 2.2, written since Draco 1.3
  if (flags & kMetadataFlag) {
    const std::uint64_t attribute_metadata = in.varint("attribute metadata count");
    for (std::uint64_t i = 0; i < attribute_metadata; ++i) {
      in.varint("attribute metadata id");
      in.metadata_element(0);
    }
    in.metadata_element(0);  // the geometry's
  }
  if (!mesh) return claims;
  if (!claims.edgebreaker) {
    claims.faces = current ? in.varint("face count") : in.u32("face count");
    claims.vertices = current ? in.varint("point count") : in.u32("point count");
  } else if (current) {
    in.u8("traversal type");
    claims.vertices = in.varint("vertex count");
    claims.faces = in.varint("face count");
    in.u8("attribute data count");
    const std::uint64_t symbols = in.varint("symbol count");
    const std::uint64_t split_symbols = in.varint("split symbol count");
    if (symbols > *claims.faces || split_symbols > symbols) cut_off("more symbols than faces");
    *claims.vertices += split_symbols;  // the decoder sizes its vertex arrays for both
  } else {
    // Before 2.2 the counts start with the new vertices of split events,
    // written as u32 before 2.0 and as varints since.
    const bool varints = version >= 2 * 256;
    auto count = [&](const char* what) { return varints ? in.varint(what) : in.u32(what); };
    in.u8("traversal type");
    const std::uint64_t new_vertices = count("new vertex count");
    claims.vertices = count("vertex count") + new_vertices;
    claims.faces = count("face count");
  }
  return claims;
}

void check_draco_claims(const DracoClaims& claims, std::size_t data_size, const DecodeLimits& limits) {
  if (claims.faces) {
    check_triangle_limit(*claims.faces, limits, "Draco");
    if (*claims.faces > kDracoFacesPerByte * data_size)
      throw Error(ErrorCode::malformed_input,
                  "the Draco header claims " + std::to_string(*claims.faces) + " faces, more than " +
                      std::to_string(data_size) + " bytes can encode; the file is corrupt");
  }
  // A closed mesh has about half as many vertices as faces, an open one up
  // to three per face.
  const std::uint64_t max_vertices = 3 * (claims.faces ? *claims.faces : limits.max_triangles) + 3;
  if (claims.vertices && *claims.vertices > max_vertices)
    throw Error(ErrorCode::malformed_input, "the Draco header claims " + std::to_string(*claims.vertices) +
                                                " vertices for its faces; the file is corrupt");
}

}  // namespace voxd::mesh_io
