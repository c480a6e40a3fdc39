#pragma once
// Detection helpers shared with decode_mesh's error messages.
#include <cstdint>
#include <span>
#include <string_view>

namespace voxd::mesh_io {

// Names well-known non-mesh content (ZIP/3MF, glb, images...), or empty.
std::string_view foreign_format_name(std::span<const std::uint8_t> data);

}  // namespace voxd::mesh_io
