#pragma once
// What the mesh writers share (thickness_mesh.cpp, mesh_export.cpp): the
// glTF 2.0 binary container (the JSON chunk padded to 4 bytes, then the BIN
// chunk) and the scene under one root node that turns CAD's Z-up model axes
// to glTF's Y-up; PLY's binary face list. Everything goes through a
// ByteBuffer flushed as it grows, so a file is never held twice.
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>

#include <nlohmann/json.hpp>

#include "encode/byte_buffer.h"
#include "voxd/byte_sink.h"
#include "voxd/error.h"

namespace voxd::encode {

template <class T>
void put_value(ByteBuffer& out, const T& v) {
  out.put_bytes(&v, sizeof v);
}

// Flushes `out` into `sink` once it is large.
inline void flush_if_large(ByteBuffer& out, ByteSink& sink) {
  if (out.size() < (std::size_t{4} << 20)) return;
  sink.write(out.bytes());
  out.reset();
}

// PLY's faces, each "uchar 3, int a b c" (binary little-endian).
template <class Triangles>
void put_ply_faces(const Triangles& triangles, ByteBuffer& out, ByteSink& sink) {
  for (const auto& t : triangles) {
    out.put_byte(3);
    for (const std::uint32_t v : t) put_value(out, static_cast<std::int32_t>(v));
    flush_if_large(out, sink);
  }
}

// asset, scene and nodes: node 0 the part (mesh 0), node 1 the root.
inline nlohmann::json gltf_z_up_scene() {
  const double half = std::sqrt(0.5);
  return {{"asset", {{"version", "2.0"}, {"generator", "voxd"}}},
          {"scene", 0},
          {"scenes", nlohmann::json::array({{{"nodes", nlohmann::json::array({1})}}})},
          {"nodes", nlohmann::json::array({{{"name", "part"}, {"mesh", 0}},
                                           {{"name", "voxd model (Z-up model axes turned to glTF's Y-up)"},
                                            {"rotation", {-half, 0.0, 0.0, half}},
                                            {"children", nlohmann::json::array({0})}}})}};
}

// glTF forbids empty accessors and buffers: an empty part is an empty scene.
inline nlohmann::json gltf_empty_scene() {
  return {{"asset", {{"version", "2.0"}, {"generator", "voxd"}}}, {"scene", 0},
          {"scenes", nlohmann::json::array({nlohmann::json::object()})}};
}

// `write_bin` puts exactly `bin_size` bytes (when `gltf` has buffers).
inline void write_glb(const nlohmann::json& gltf, std::uint64_t bin_size,
                      const std::function<void(ByteBuffer&, ByteSink&)>& write_bin, ByteSink& sink) {
  std::string json = gltf.dump();
  json.resize((json.size() + 3) & ~std::size_t{3}, ' ');
  const bool with_bin = gltf.contains("buffers");
  const std::uint64_t total = 12 + 8 + json.size() + (with_bin ? 8 + bin_size : 0);
  if (total > std::numeric_limits<std::uint32_t>::max())
    throw Error(ErrorCode::limit_exceeded,
                "GLB writer: the file would take " + std::to_string(total) + " bytes, more than GLB's 4 GiB");
  ByteBuffer out;
  out.reset();
  put_value(out, std::uint32_t{0x46546C67});  // "glTF"
  put_value(out, std::uint32_t{2});
  put_value(out, static_cast<std::uint32_t>(total));
  put_value(out, static_cast<std::uint32_t>(json.size()));
  put_value(out, std::uint32_t{0x4E4F534A});  // "JSON"
  out.put_bytes(json.data(), json.size());
  if (with_bin) {
    put_value(out, static_cast<std::uint32_t>(bin_size));
    put_value(out, std::uint32_t{0x004E4942});  // "BIN\0"
    write_bin(out, sink);
  }
  sink.write(out.bytes());
}

}  // namespace voxd::encode
