// Entry points of mesh decoding: the checks every format shares (empty input,
// size limit), detection, and dispatch to the per-format decoders.
#include <string>

#include "mesh_io/decode_checks.h"
#include "mesh_io/detect_format.h"
#include "mesh_io/format_decoders.h"
#include "mesh_io/text_encoding.h"
#include "voxd/error.h"
#include "voxd/mesh_io/mesh_decode.h"

namespace voxd {
namespace {

constexpr const char* kSupportedFormats =
    "supported formats are binary STL, ASCII STL, OBJ, PLY (ascii or binary) and Draco (.drc)";

void check_size(std::span<const std::uint8_t> data, const DecodeLimits& limits) {
  if (data.empty()) throw Error(ErrorCode::empty_input, "the mesh file is empty (0 bytes); upload it again");
  if (data.size() > limits.max_bytes)
    throw Error(ErrorCode::limit_exceeded, "the mesh file is " + std::to_string(data.size()) +
                                               " bytes, over the limit of " + std::to_string(limits.max_bytes) +
                                               " bytes; compress it (e.g. to Draco) or simplify the mesh");
}

std::string_view as_text(std::span<const std::uint8_t> data) {
  return {reinterpret_cast<const char*>(data.data()), data.size()};
}

}  // namespace

Mesh decode_mesh(std::span<const std::uint8_t> data, std::string_view name_hint, const DecodeLimits& limits,
                 DecodeWarnings* warnings) {
  check_size(data, limits);
  return decode_detected_mesh(detect_mesh_format(data, name_hint), data, name_hint, limits, warnings);
}

Mesh decode_detected_mesh(MeshFormat detected, std::span<const std::uint8_t> data, std::string_view name_hint,
                          const DecodeLimits& limits, DecodeWarnings* warnings) {
  check_size(data, limits);
  // UTF-16 text (a binary STL of exactly its declared size stays one, BOM-like
  // header or not): decoded to UTF-8, then read as any text.
  if (const auto order = mesh_io::utf16_byte_order(data); order && detected != MeshFormat::stl_binary) {
    const std::string text = mesh_io::utf16_to_utf8(data, *order);
    if (warnings)
      warnings->push_back(std::string("the file is UTF-16 text (") +
                          (*order == mesh_io::Utf16Order::big_endian ? "big" : "little") +
                          "-endian), read as UTF-8; save it as UTF-8 for tools that expect it");
    return decode_mesh({reinterpret_cast<const std::uint8_t*>(text.data()), text.size()}, name_hint, limits, warnings);
  }
  if (detected == MeshFormat::unknown) {
    const std::string name = name_hint.empty() ? std::string("the file") : mesh_io::quote_token(name_hint);
    const std::string_view foreign = mesh_io::foreign_format_name(data);
    const std::string what = foreign.empty() ? "starts with " + mesh_io::quote_token(as_text(data).substr(0, 16))
                                             : "looks like " + std::string(foreign);
    throw Error(ErrorCode::unknown_format,
                "cannot recognize the mesh format of " + name + ", which " + what + "; " + kSupportedFormats);
  }
  return decode_mesh_as(detected, data, limits, warnings);
}

Mesh decode_mesh_as(MeshFormat format, std::span<const std::uint8_t> data, const DecodeLimits& limits,
                    DecodeWarnings* warnings) {
  check_size(data, limits);
  switch (format) {
    case MeshFormat::stl_binary: return mesh_io::decode_stl_binary(data, limits);
    case MeshFormat::stl_ascii: return mesh_io::decode_stl_ascii(as_text(data), limits);
    case MeshFormat::obj: return mesh_io::decode_obj(as_text(data), limits);
    case MeshFormat::ply: return mesh_io::decode_ply(data, limits, warnings);
    case MeshFormat::draco: return mesh_io::decode_draco(data, limits);
    case MeshFormat::unknown: break;
  }
  throw Error(ErrorCode::unknown_format, std::string("no decoder for format '") + to_string(format) + "'; " +
                                             kSupportedFormats);
}

}  // namespace voxd
