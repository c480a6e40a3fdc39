#pragma once
// Identity of a submission: SHA-256 over the mesh bytes and the canonical
// parameters, so a CAD plugin resubmitting the same part is answered from the
// finished result.
#include <cstdint>
#include <span>
#include <string>

namespace voxd::server {

// Lowercase hex SHA-256 of (mesh bytes, 0x00, canonical params JSON text).
std::string content_hash(std::span<const std::uint8_t> mesh_bytes, const std::string& canonical_params);

}  // namespace voxd::server
