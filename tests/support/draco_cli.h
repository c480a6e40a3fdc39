#pragma once
// Encodes meshes with Debian's draco_encoder command, an encoder independent
// of the decoder under test.
#include <cstdint>
#include <string>
#include <vector>

#include "voxd/mesh.h"

namespace voxd::test {

inline constexpr const char* kDracoEncoder = "/usr/bin/draco_encoder";

bool draco_encoder_available();

// Writes `mesh` as OBJ to a temporary folder and runs
// `draco_encoder -i mesh.obj -o mesh.drc <flags>`; throws std::runtime_error
// with the command's output if it fails.
std::vector<std::uint8_t> encode_with_draco_encoder(const Mesh& mesh, const std::string& flags);

}  // namespace voxd::test
