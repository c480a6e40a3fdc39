#include "voxd/encode/thickness_mesh.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include <glm/common.hpp>
#include <nlohmann/json.hpp>

#include "encode/byte_buffer.h"
#include "encode/mesh_file.h"
#include "voxd/analysis/surface_thickness.h"
#include "voxd/error.h"

namespace voxd {

using encode::ByteBuffer;
using encode::flush_if_large;

Rgb ThicknessColours::colour(float thickness) const {
  if (!(thickness > 0)) return kNoMaterialColour;
  const float span = high - low;
  const float at = span > 0 ? std::clamp((thickness - low) / span, 0.0f, 1.0f) : 0.5f;
  return thickness_ramp()[static_cast<std::size_t>(std::lround(at * 255.0f))];
}

namespace {

void check_values(const Mesh& mesh, std::span<const float> thickness, const char* writer) {
  if (thickness.size() != mesh.vertices.size())
    throw Error(ErrorCode::invalid_argument, std::string(writer) + ": " + std::to_string(thickness.size()) +
                                                 " thickness values for " + std::to_string(mesh.vertices.size()) +
                                                 " vertices");
}

template <class T>
void put(ByteBuffer& out, const T& v) {
  encode::put_value(out, v);
}

// sRGB 8-bit to linear, as glTF's COLOR_0 is.
float linear(std::uint8_t c) {
  const double s = c / 255.0;
  return static_cast<float>(s <= 0.04045 ? s / 12.92 : std::pow((s + 0.055) / 1.055, 2.4));
}

}  // namespace

void write_thickness_ply(const Mesh& mesh, std::span<const float> thickness, const ThicknessColours& colours,
                         const std::string& unit, ByteSink& sink) {
  check_values(mesh, thickness, "PLY writer");
  const std::string header = "ply\nformat binary_little_endian 1.0\ncomment voxd wall thickness per vertex, in " + unit +
                             " (0: no filled voxel under the vertex)\nelement vertex " +
                             std::to_string(mesh.vertices.size()) +
                             "\nproperty float x\nproperty float y\nproperty float z\nproperty float thickness\n"
                             "property uchar red\nproperty uchar green\nproperty uchar blue\nelement face " +
                             std::to_string(mesh.triangles.size()) + "\nproperty list uchar int vertex_indices\nend_header\n";
  ByteBuffer out;
  out.reset();
  out.put_bytes(header.data(), header.size());
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    put(out, mesh.vertices[i]);
    put(out, thickness[i]);
    const Rgb c = colours.colour(thickness[i]);
    put(out, c);
    flush_if_large(out, sink);
  }
  encode::put_ply_faces(mesh.triangles, out, sink);
  sink.write(out.bytes());
}

void write_thickness_glb(const Mesh& mesh, std::span<const float> thickness, const ThicknessColours& colours,
                         const std::string& unit, ByteSink& sink) {
  check_values(mesh, thickness, "GLB writer");
  // Triangles with a repeated corner draw nothing; the validator flags them.
  std::vector<std::array<std::uint32_t, 3>> triangles;
  triangles.reserve(mesh.triangles.size());
  for (const auto& t : mesh.triangles)
    if (t[0] != t[1] && t[1] != t[2] && t[0] != t[2]) triangles.push_back(t);
  const std::size_t n = mesh.vertices.size();
  std::vector<glm::vec3> normals = vertex_normals(mesh);
  for (glm::vec3& v : normals)
    if (v == glm::vec3(0.0f)) v = glm::vec3(0, 0, 1);  // a vertex of zero-area triangles only: any unit normal

  glm::vec3 lo(std::numeric_limits<float>::max()), hi(std::numeric_limits<float>::lowest());
  for (const glm::vec3& p : mesh.vertices) lo = glm::min(lo, p), hi = glm::max(hi, p);
  float tmin = std::numeric_limits<float>::max(), tmax = std::numeric_limits<float>::lowest();
  for (const float t : thickness) tmin = std::min(tmin, t), tmax = std::max(tmax, t);
  glm::vec3 clo(1.0f), chi(0.0f);
  std::vector<glm::vec3> linear_colours(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Rgb c = colours.colour(thickness[i]);
    linear_colours[i] = {linear(c.r), linear(c.g), linear(c.b)};
    clo = glm::min(clo, linear_colours[i]);
    chi = glm::max(chi, linear_colours[i]);
  }

  // The BIN chunk: positions, normals, colours, thickness, indices; every
  // part a multiple of 4 bytes.
  const std::uint64_t v3 = 12 * static_cast<std::uint64_t>(n);
  const std::uint64_t offsets[] = {0, v3, 2 * v3, 3 * v3, 3 * v3 + 4 * n};
  const std::uint64_t index_bytes = 12 * static_cast<std::uint64_t>(triangles.size());
  const std::uint64_t bin_size = offsets[4] + index_bytes;
  auto vec3 = [](const glm::vec3& v) { return nlohmann::json::array({v.x, v.y, v.z}); };
  nlohmann::json views = nlohmann::json::array(), accessors = nlohmann::json::array();
  auto view = [&](std::uint64_t offset, std::uint64_t length, int target) {
    views.push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", length}, {"target", target}});
    return views.size() - 1;
  };
  constexpr int kFloat = 5126, kUnsignedInt = 5125, kArrayBuffer = 34962, kElementArrayBuffer = 34963;
  accessors.push_back({{"bufferView", view(offsets[0], v3, kArrayBuffer)}, {"componentType", kFloat}, {"count", n},
                       {"type", "VEC3"}, {"min", vec3(lo)}, {"max", vec3(hi)}});
  accessors.push_back(
      {{"bufferView", view(offsets[1], v3, kArrayBuffer)}, {"componentType", kFloat}, {"count", n}, {"type", "VEC3"}});
  accessors.push_back({{"bufferView", view(offsets[2], v3, kArrayBuffer)}, {"componentType", kFloat}, {"count", n},
                       {"type", "VEC3"}, {"min", vec3(clo)}, {"max", vec3(chi)}});
  accessors.push_back({{"bufferView", view(offsets[3], 4 * n, kArrayBuffer)}, {"componentType", kFloat}, {"count", n},
                       {"type", "SCALAR"}, {"min", nlohmann::json::array({tmin})}, {"max", nlohmann::json::array({tmax})}});
  accessors.push_back({{"bufferView", view(offsets[4], index_bytes, kElementArrayBuffer)},
                       {"componentType", kUnsignedInt},
                       {"count", 3 * triangles.size()},
                       {"type", "SCALAR"}});
  nlohmann::json gltf = encode::gltf_z_up_scene();
  gltf.update({
      {"materials", nlohmann::json::array({{{"name", "wall thickness (vertex colours)"},
                                            {"pbrMetallicRoughness", {{"metallicFactor", 0.0}, {"roughnessFactor", 1.0}}},
                                            {"doubleSided", true}}})},
      {"meshes", nlohmann::json::array({{{"name", "wall thickness, " + unit},
                                         {"primitives", nlohmann::json::array({{{"attributes",
                                                                                 {{"POSITION", 0},
                                                                                  {"NORMAL", 1},
                                                                                  {"COLOR_0", 2},
                                                                                  {"_THICKNESS", 3}}},
                                                                                {"indices", 4},
                                                                                {"material", 0},
                                                                                {"mode", 4}}})}}})},
      {"accessors", accessors},
      {"bufferViews", views},
      {"buffers", nlohmann::json::array({{{"byteLength", bin_size}}})}});
  if (n == 0 || triangles.empty()) gltf = encode::gltf_empty_scene();
  encode::write_glb(gltf, bin_size, [&](ByteBuffer& out, ByteSink& to) {
    for (const glm::vec3& p : mesh.vertices) put(out, p);
    flush_if_large(out, to);
    for (const glm::vec3& v : normals) put(out, v);
    flush_if_large(out, to);
    for (const glm::vec3& c : linear_colours) put(out, c);
    flush_if_large(out, to);
    out.put_bytes(thickness.data(), 4 * n);
    for (const auto& t : triangles) {
      put(out, t);
      flush_if_large(out, to);
    }
  }, sink);
}

}  // namespace voxd
