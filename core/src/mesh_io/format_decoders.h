#pragma once
// One decoder per format, behind decode_mesh_as(). Each validates what only it
// can see (syntax, record sizes, header counts) and names the line, byte
// offset or element where the data went wrong. Size and emptiness checks that
// apply to every format happen before these are called.
#include <cstdint>
#include <span>
#include <string_view>

#include "voxd/mesh.h"
#include "voxd/mesh_io/mesh_decode.h"

namespace voxd::mesh_io {

Mesh decode_stl_binary(std::span<const std::uint8_t> data, const DecodeLimits& limits);
Mesh decode_stl_ascii(std::string_view text, const DecodeLimits& limits);
Mesh decode_obj(std::string_view text, const DecodeLimits& limits);
Mesh decode_ply(std::span<const std::uint8_t> data, const DecodeLimits& limits, DecodeWarnings* warnings);
Mesh decode_draco(std::span<const std::uint8_t> data, const DecodeLimits& limits);

}  // namespace voxd::mesh_io
