#pragma once
// What a Draco file's header claims, read and checked before libdraco sees
// the data. libdraco sizes its buffers from these counts (a 74-byte file
// claiming 3.4e9 faces made it reserve 13 GB), so they are held against the
// service's triangle limit and against the bytes actually present.
// Layout from the Draco bitstream specification: "DRACO", version major and
// minor, encoder type, method, flags (u16); metadata when flagged; then the
// connectivity header of the sequential or the edgebreaker method, in the
// layouts of bitstreams 1.x, 2.0/2.1 and 2.2.
#include <cstdint>
#include <optional>
#include <span>

#include "voxd/mesh_io/mesh_decode.h"

namespace voxd::mesh_io {

struct DracoClaims {
  int version_major = 0, version_minor = 0;
  bool edgebreaker = false;
  // Unset for a point cloud (which the decoder refuses).
  std::optional<std::uint64_t> faces, vertices;
};

// Reads the header (throws malformed_input when it is cut off or invalid).
DracoClaims read_draco_claims(std::span<const std::uint8_t> data);

// Throws limit_exceeded or malformed_input when the claims are over the
// triangle limit or more than the bytes present can encode: even the most
// regular mesh needs more than a byte per kDracoFacesPerByte faces.
void check_draco_claims(const DracoClaims& claims, std::size_t data_size, const DecodeLimits& limits);

// Edgebreaker with entropy coding needs about 1-3 bits a face on real meshes,
// and a perfectly regular grid far less; 1024 faces a byte is beyond any of
// them and still bounds what a small file can make the decoder reserve.
inline constexpr std::uint64_t kDracoFacesPerByte = 1024;

}  // namespace voxd::mesh_io
