#include "voxd/encode/mesh_export.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>

#include "encode/byte_buffer.h"
#include "encode/mesh_file.h"
#include "voxd/error.h"

namespace voxd {

using encode::ByteBuffer;
using encode::flush_if_large;

namespace {

template <class T>
void put(ByteBuffer& out, const T& v) {
  encode::put_value(out, v);
}

}  // namespace

void write_mesh_stl(const Mesh& mesh, const std::string& description, ByteSink& sink) {
  if (mesh.triangles.size() > std::numeric_limits<std::uint32_t>::max())
    throw Error(ErrorCode::limit_exceeded, "STL writer: " + std::to_string(mesh.triangles.size()) +
                                               " triangles, more than binary STL's 32-bit count can hold");
  ByteBuffer out;
  out.reset();
  // Anything but "solid" at the start, which would read as ASCII STL.
  char header[80] = {};
  std::memcpy(header, "voxd ", 5);
  std::memcpy(header + 5, description.data(), std::min<std::size_t>(description.size(), sizeof header - 5));
  out.put_bytes(header, sizeof header);
  put(out, static_cast<std::uint32_t>(mesh.triangles.size()));
  for (const auto& t : mesh.triangles) {
    const glm::vec3 a = mesh.vertices[t[0]], b = mesh.vertices[t[1]], c = mesh.vertices[t[2]];
    const glm::vec3 n = glm::cross(b - a, c - a);
    const float length = glm::length(n);
    put(out, length > 0 ? n / length : glm::vec3(0.0f));
    put(out, a);
    put(out, b);
    put(out, c);
    put(out, std::uint16_t{0});
    flush_if_large(out, sink);
  }
  sink.write(out.bytes());
}

void write_mesh_ply(const Mesh& mesh, const std::string& description, ByteSink& sink) {
  const std::string header = "ply\nformat binary_little_endian 1.0\ncomment voxd " + description + "\nelement vertex " +
                             std::to_string(mesh.vertices.size()) +
                             "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
                             std::to_string(mesh.triangles.size()) + "\nproperty list uchar int vertex_indices\nend_header\n";
  ByteBuffer out;
  out.reset();
  out.put_bytes(header.data(), header.size());
  for (const glm::vec3& p : mesh.vertices) {
    put(out, p);
    flush_if_large(out, sink);
  }
  encode::put_ply_faces(mesh.triangles, out, sink);
  sink.write(out.bytes());
}

void write_mesh_glb(const Mesh& mesh, const std::string& description, ByteSink& sink) {
  const std::uint64_t n = mesh.vertices.size(), positions = 12 * n, indices = 12 * mesh.triangles.size();
  glm::vec3 lo(std::numeric_limits<float>::max()), hi(std::numeric_limits<float>::lowest());
  for (const glm::vec3& p : mesh.vertices) lo = glm::min(lo, p), hi = glm::max(hi, p);
  auto vec3 = [](const glm::vec3& v) { return nlohmann::json::array({v.x, v.y, v.z}); };
  constexpr int kFloat = 5126, kUnsignedInt = 5125, kArrayBuffer = 34962, kElementArrayBuffer = 34963;
  nlohmann::json gltf = encode::gltf_z_up_scene();
  gltf.update({
      {"materials", nlohmann::json::array({{{"name", "part"},
                                            {"pbrMetallicRoughness",
                                             {{"baseColorFactor", {0.55, 0.6, 0.68, 1.0}},
                                              {"metallicFactor", 0.0},
                                              {"roughnessFactor", 1.0}}}}})},
      {"meshes", nlohmann::json::array({{{"name", description},
                                         {"primitives", nlohmann::json::array({{{"attributes", {{"POSITION", 0}}},
                                                                                {"indices", 1},
                                                                                {"material", 0},
                                                                                {"mode", 4}}})}}})},
      {"accessors", nlohmann::json::array({{{"bufferView", 0}, {"componentType", kFloat}, {"count", n}, {"type", "VEC3"},
                                            {"min", vec3(lo)}, {"max", vec3(hi)}},
                                           {{"bufferView", 1}, {"componentType", kUnsignedInt},
                                            {"count", 3 * mesh.triangles.size()}, {"type", "SCALAR"}}})},
      {"bufferViews", nlohmann::json::array({{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", positions}, {"target", kArrayBuffer}},
                                             {{"buffer", 0}, {"byteOffset", positions}, {"byteLength", indices},
                                              {"target", kElementArrayBuffer}}})},
      {"buffers", nlohmann::json::array({{{"byteLength", positions + indices}}})}});
  if (n == 0 || mesh.triangles.empty()) gltf = encode::gltf_empty_scene();
  encode::write_glb(gltf, positions + indices, [&](ByteBuffer& out, ByteSink& to) {
    for (const glm::vec3& p : mesh.vertices) {
      put(out, p);
      flush_if_large(out, to);
    }
    for (const auto& t : mesh.triangles) {
      put(out, t);
      flush_if_large(out, to);
    }
  }, sink);
}

}  // namespace voxd
