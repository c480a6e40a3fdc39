#pragma once
// Decoding meshes from memory. The format is detected from the content; the
// file name is only a hint used when content is ambiguous.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "voxd/mesh.h"
#include "voxd/enum_names.h"

namespace voxd {

enum class MeshFormat { unknown, stl_binary, stl_ascii, obj, ply, draco };

inline constexpr EnumNames<MeshFormat, 6> kMeshFormatNames{{
    {MeshFormat::unknown, "unknown"}, {MeshFormat::stl_binary, "stl_binary"}, {MeshFormat::stl_ascii, "stl_ascii"},
    {MeshFormat::obj, "obj"}, {MeshFormat::ply, "ply"}, {MeshFormat::draco, "draco"}}};
inline const char* to_string(MeshFormat format) noexcept { return name_of(kMeshFormatNames, format); }

struct DecodeLimits {
  std::size_t max_bytes = std::size_t{2} << 30;  // 2 GiB
  std::size_t max_triangles = 50'000'000;
  // Draco is decoded by a third-party library (libdraco). When set, this
  // decodes it instead of the in-process call, after the header's counts are
  // checked: the service runs libdraco in a child process under memory and
  // CPU limits (server/draco_isolation.h), so nothing it does can take the
  // service down. It returns the mesh as decode_mesh would, or throws Error.
  std::function<Mesh(std::span<const std::uint8_t>)> draco_decoder;
};

// What a decoder read otherwise than the file says outright, as sentences a
// user can act on: UTF-16 text decoded, a header line it did not know taken
// as a comment. The geometry is the file's; the source may want a look.
using DecodeWarnings = std::vector<std::string>;

// Detection only; never throws. Returns MeshFormat::unknown when nothing fits.
MeshFormat detect_mesh_format(std::span<const std::uint8_t> data, std::string_view name_hint = {});

// Decodes, validates (finite coordinates, indices in range, limits) and drops
// triangles whose indices repeat. Text in UTF-16 (with its byte order mark,
// as Windows tools save it) is decoded as UTF-8. Throws voxd::Error with a
// user-actionable message; never crashes or hangs on hostile input. Adds to
// `warnings`, when given, what the file should have said otherwise.
Mesh decode_mesh(std::span<const std::uint8_t> data, std::string_view name_hint = {},
                 const DecodeLimits& limits = {}, DecodeWarnings* warnings = nullptr);

// decode_mesh for a caller that detected the format first (to size the
// memory decoding takes): `detected` is detect_mesh_format(data, name_hint),
// and is not detected again.
Mesh decode_detected_mesh(MeshFormat detected, std::span<const std::uint8_t> data, std::string_view name_hint = {},
                          const DecodeLimits& limits = {}, DecodeWarnings* warnings = nullptr);

// Decodes with an already known format (used by tests and by decode_mesh).
Mesh decode_mesh_as(MeshFormat format, std::span<const std::uint8_t> data,
                    const DecodeLimits& limits = {}, DecodeWarnings* warnings = nullptr);

}  // namespace voxd
