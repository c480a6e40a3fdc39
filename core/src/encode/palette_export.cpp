// Palette reconstructions as STL and instanced glTF; see voxd/encode/palette_export.h.
#include "voxd/encode/palette_export.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>

#include "encode/byte_buffer.h"
#include "encode/volume_checks.h"
#include "voxd/error.h"
#include "voxd/voxelize/palette_geometry.h"

namespace voxd {
namespace {

// Both formats are little-endian; the floats and integers are copied as they are.
static_assert(std::endian::native == std::endian::little, "the palette writers assume a little-endian host");

using encode::ByteBuffer;

constexpr std::size_t kFlushBytes = std::size_t{1} << 20;
// Volumes within these of 0 or 1 are empty or full: the clipping's rounding.
constexpr double kVolumeTolerance = 1e-9;

enum class Kind { empty, partial, full };

// Cube faces in the order of the neighbour directions -x, +x, -y, +y, -z, +z,
// each as two counter-clockwise triangles seen from outside.
constexpr int kCubeFaces[6][2][3][3] = {
    {{{0, 0, 0}, {0, 0, 1}, {0, 1, 1}}, {{0, 0, 0}, {0, 1, 1}, {0, 1, 0}}},
    {{{1, 0, 0}, {1, 1, 0}, {1, 1, 1}}, {{1, 0, 0}, {1, 1, 1}, {1, 0, 1}}},
    {{{0, 0, 0}, {1, 0, 0}, {1, 0, 1}}, {{0, 0, 0}, {1, 0, 1}, {0, 0, 1}}},
    {{{0, 1, 0}, {0, 1, 1}, {1, 1, 1}}, {{0, 1, 0}, {1, 1, 1}, {1, 1, 0}}},
    {{{0, 0, 0}, {0, 1, 0}, {1, 1, 0}}, {{0, 0, 0}, {1, 1, 0}, {1, 0, 0}}},
    {{{0, 0, 1}, {1, 0, 1}, {1, 1, 1}}, {{0, 0, 1}, {1, 1, 1}, {0, 1, 1}}},
};

struct Triangle {
  std::array<glm::dvec3, 3> corners;  // offsets from the voxel's minimum corner, model units
  glm::dvec3 normal{0.0};
};

// One palette element, ready to be placed: its triangles scaled to the voxel
// size. A full element's are the cube's, two per face in kCubeFaces order.
struct Shape {
  Kind kind = Kind::empty;
  std::vector<Triangle> triangles;
};

Triangle make_triangle(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, const glm::dvec3& size) {
  Triangle t{{a * size, b * size, c * size}, glm::dvec3(0.0)};
  // From the scaled corners: a stretch tilts the normals of slanted faces.
  const glm::dvec3 n = glm::cross(t.corners[1] - t.corners[0], t.corners[2] - t.corners[0]);
  const double length = glm::length(n);
  if (length > 0.0) t.normal = n / length;
  return t;
}

Shape make_shape(const PaletteElement& element, const glm::dvec3& size) {
  Shape shape;
  const bool has_full_piece =
      std::any_of(element.pieces.begin(), element.pieces.end(), [](const ConvexPiece& p) { return p.empty(); });
  const double volume = has_full_piece ? 1.0 : element_volume(element);
  if (volume <= kVolumeTolerance) return shape;
  if (volume >= 1.0 - kVolumeTolerance) {
    shape.kind = Kind::full;
    for (const auto& face : kCubeFaces)
      for (const auto& t : face)
        shape.triangles.push_back(make_triangle(glm::dvec3(t[0][0], t[0][1], t[0][2]),
                                                glm::dvec3(t[1][0], t[1][1], t[1][2]),
                                                glm::dvec3(t[2][0], t[2][1], t[2][2]), size));
    return shape;
  }
  shape.kind = Kind::partial;
  const ElementMesh mesh = element_mesh(element);
  for (const auto& t : mesh.triangles)
    shape.triangles.push_back(make_triangle(mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]], size));
  return shape;
}

// What both writers need: the shapes, by element index, and the volume.
class Reconstruction {
 public:
  Reconstruction(const Palette& palette, const DenseVolume<std::uint8_t>& volume, const glm::dvec3& voxel_scale,
                 const char* writer)
      : volume_(volume), grid_(volume.grid()) {
    encode::require_voxels(volume, writer);
    for (int a = 0; a < 3; ++a) {
      size_[a] = grid_.voxel_size * voxel_scale[a];
      if (!std::isfinite(size_[a]) || !(size_[a] > 0.0))
        throw Error(ErrorCode::invalid_argument,
                    std::string(writer) + ": voxel_size times voxel_scale must be positive and finite on every axis");
      origin_[a] = grid_.origin[a] * voxel_scale[a];
      if (!std::isfinite(origin_[a]))
        throw Error(ErrorCode::invalid_argument, std::string(writer) + ": the grid origin must be finite");
    }
    if (palette.elements.size() > kMaxPaletteElements)
      throw Error(ErrorCode::invalid_argument, std::string(writer) + ": the palette has more than " +
                                                   std::to_string(kMaxPaletteElements) + " elements");
    shapes_.resize(palette.elements.size());
    for (std::size_t e = 0; e < palette.elements.size(); ++e) {
      shapes_[e] = make_shape(palette.elements[e], size_);
      full_[e] = shapes_[e].kind == Kind::full;
    }
    check_indices(writer);
  }

  const Grid& grid() const { return grid_; }
  const glm::dvec3& size() const { return size_; }
  const Shape& shape(std::uint8_t e) const { return shapes_[e]; }
  std::size_t element_count() const { return shapes_.size(); }
  const std::uint8_t* slab(std::int64_t k) const { return volume_.slab(k); }

  // Bit f set when the 6-neighbour in direction f (kCubeFaces order) is not
  // a full voxel: the faces a full voxel shows.
  unsigned exposed_faces(std::int64_t i, std::int64_t j, std::int64_t k) const {
    const glm::i64vec3& d = grid_.dims;
    const std::uint8_t* v = volume_.values().data() + volume_.index(i, j, k);
    const std::int64_t sx = 1, sy = d.x, sz = d.x * d.y;
    unsigned mask = 0;
    if (i == 0 || !full_[v[-sx]]) mask |= 1u << 0;
    if (i == d.x - 1 || !full_[v[sx]]) mask |= 1u << 1;
    if (j == 0 || !full_[v[-sy]]) mask |= 1u << 2;
    if (j == d.y - 1 || !full_[v[sy]]) mask |= 1u << 3;
    if (k == 0 || !full_[v[-sz]]) mask |= 1u << 4;
    if (k == d.z - 1 || !full_[v[sz]]) mask |= 1u << 5;
    return mask;
  }

  // Minimum corner of voxel (i, j, k) in model units.
  glm::dvec3 corner(std::int64_t i, std::int64_t j, std::int64_t k) const {
    return origin_ + glm::dvec3(static_cast<double>(i), static_cast<double>(j), static_cast<double>(k)) * size_;
  }

 private:
  void check_indices(const char* writer) const {
    const glm::i64vec3& d = grid_.dims;
    for (std::int64_t k = 0; k < d.z; ++k) {
      const std::uint8_t* s = volume_.slab(k);
      for (std::int64_t n = 0; n < d.x * d.y; ++n)
        if (s[n] >= shapes_.size())
          throw Error(ErrorCode::invalid_argument,
                      std::string(writer) + ": voxel (" + std::to_string(n % d.x) + ", " + std::to_string(n / d.x) +
                          ", " + std::to_string(k) + ") has element " + std::to_string(s[n]) + ", the palette has " +
                          std::to_string(shapes_.size()));
    }
  }

  const DenseVolume<std::uint8_t>& volume_;
  const Grid& grid_;
  glm::dvec3 size_{1.0};
  glm::dvec3 origin_{0.0};
  std::vector<Shape> shapes_;
  std::array<bool, 256> full_{};  // by element index; indices past the palette never occur (checked)
};

void put_float3(ByteBuffer& out, const glm::dvec3& v) {
  const float f[3] = {static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z)};
  out.put_bytes(f, sizeof f);
}

void put_u32(ByteBuffer& out, std::uint32_t v) { out.put_bytes(&v, sizeof v); }

// ------------------------------------------------------------------- STL --

void put_facet(ByteBuffer& out, const Triangle& t, const glm::dvec3& base) {
  put_float3(out, t.normal);
  for (const glm::dvec3& c : t.corners) put_float3(out, base + c);
  const std::uint16_t attribute = 0;
  out.put_bytes(&attribute, sizeof attribute);
}

// Sends what `out` holds once it is large: a row at a time, so even a slab
// of partial elements (8 triangles, 400 bytes each) is never held whole.
void flush_if_large(ByteBuffer& out, ByteSink& sink) {
  if (out.size() < kFlushBytes) return;
  sink.write(out.bytes());
  out.reset();
}

// Triangles of one slab; with `out` null it only counts them.
std::uint64_t stl_slab(const Reconstruction& r, std::int64_t k, ByteBuffer* out, ByteSink* sink) {
  const glm::i64vec3& d = r.grid().dims;
  const std::uint8_t* s = r.slab(k);
  std::uint64_t count = 0;
  for (std::int64_t j = 0; j < d.y; ++j) {
    if (out) flush_if_large(*out, *sink);
    for (std::int64_t i = 0; i < d.x; ++i) {
      const Shape& shape = r.shape(s[i + d.x * j]);
      if (shape.kind == Kind::empty) continue;
      if (shape.kind == Kind::partial) {
        count += shape.triangles.size();
        if (out)
          for (const Triangle& t : shape.triangles) put_facet(*out, t, r.corner(i, j, k));
        continue;
      }
      const unsigned faces = r.exposed_faces(i, j, k);
      count += 2 * static_cast<std::uint64_t>(std::popcount(faces));
      if (out)
        for (unsigned f = 0; f < 6; ++f)
          if (faces & (1u << f)) {
            put_facet(*out, shape.triangles[2 * f], r.corner(i, j, k));
            put_facet(*out, shape.triangles[2 * f + 1], r.corner(i, j, k));
          }
    }
  }
  return count;
}

// ------------------------------------------------------------------- GLB --

constexpr std::uint32_t kGlbMagic = 0x46546C67;      // "glTF"
constexpr std::uint32_t kChunkJson = 0x4E4F534A;     // "JSON"
constexpr std::uint32_t kChunkBin = 0x004E4942;      // "BIN\0"
constexpr int kFloat = 5126;                         // accessor componentType
constexpr int kArrayBuffer = 34962;                  // bufferView target of vertex attributes
constexpr const char* kInstancing = "EXT_mesh_gpu_instancing";

std::size_t padded4(std::size_t n) { return (n + 3) & ~std::size_t{3}; }

// Instances of one element, from the counting pass.
struct Instances {
  std::uint64_t count = 0;
  glm::i64vec3 min{std::numeric_limits<std::int64_t>::max()};
  glm::i64vec3 max{std::numeric_limits<std::int64_t>::min()};
};

// Whether voxel (i, j, k), of element e, is drawn: any non-empty element,
// a full one only where it is exposed.
bool instanced(const Reconstruction& r, std::uint8_t e, std::int64_t i, std::int64_t j, std::int64_t k) {
  const Kind kind = r.shape(e).kind;
  return kind == Kind::partial || (kind == Kind::full && r.exposed_faces(i, j, k) != 0);
}

nlohmann::json float3_json(const glm::dvec3& v) {
  return nlohmann::json::array({static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z)});
}

}  // namespace

void write_palette_stl(const Palette& palette, const DenseVolume<std::uint8_t>& element,
                       const glm::dvec3& voxel_scale, ByteSink& sink) {
  const Reconstruction r(palette, element, voxel_scale, "STL writer");
  const std::int64_t nz = r.grid().dims.z;

  std::uint64_t total = 0;
  for (std::int64_t k = 0; k < nz; ++k) total += stl_slab(r, k, nullptr, nullptr);
  if (total > std::numeric_limits<std::uint32_t>::max())
    throw Error(ErrorCode::limit_exceeded, "STL writer: " + std::to_string(total) +
                                               " triangles, more than binary STL's 32-bit count can hold");

  ByteBuffer out;
  out.reset();
  // Anything but "solid" at the start, which would read as ASCII STL.
  char header[80] = {};
  constexpr char kTitle[] = "voxd palette reconstruction";
  std::memcpy(header, kTitle, sizeof kTitle - 1);
  out.put_bytes(header, sizeof header);
  put_u32(out, static_cast<std::uint32_t>(total));
  for (std::int64_t k = 0; k < nz; ++k) stl_slab(r, k, &out, &sink);
  sink.write(out.bytes());
}

void write_palette_glb(const Palette& palette, const DenseVolume<std::uint8_t>& element,
                       const glm::dvec3& voxel_scale, ByteSink& sink) {
  const Reconstruction r(palette, element, voxel_scale, "GLB writer");
  const glm::i64vec3& d = r.grid().dims;

  // One pass: each element's instances (voxel indices, x-fastest), their
  // count and extent. The indices take at most what their translations will
  // take in the file (bounded by GLB's 4 GiB), and the writing pass then
  // reads no voxel again.
  std::vector<Instances> instances(r.element_count());
  std::vector<std::vector<glm::u32vec3>> voxels(r.element_count());  // grid dims < 2^32
  for (std::int64_t k = 0; k < d.z; ++k) {
    const std::uint8_t* s = r.slab(k);
    for (std::int64_t j = 0; j < d.y; ++j)
      for (std::int64_t i = 0; i < d.x; ++i) {
        const std::uint8_t e = s[i + d.x * j];
        if (!instanced(r, e, i, j, k)) continue;
        Instances& in = instances[e];
        ++in.count;
        in.min = glm::min(in.min, glm::i64vec3(i, j, k));
        in.max = glm::max(in.max, glm::i64vec3(i, j, k));
        voxels[e].emplace_back(static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j), static_cast<std::uint32_t>(k));
      }
  }

  // The BIN chunk: every used element's positions and normals, then every
  // used element's translations. Mesh data is small and built here; the
  // translations are streamed below.
  std::vector<std::uint8_t> used;
  for (std::size_t e = 0; e < r.element_count(); ++e)
    if (instances[e].count > 0) used.push_back(static_cast<std::uint8_t>(e));

  nlohmann::json accessors = nlohmann::json::array(), views = nlohmann::json::array();
  nlohmann::json meshes = nlohmann::json::array(), nodes = nlohmann::json::array();
  ByteBuffer mesh_data;
  mesh_data.reset();
  const auto add_view = [&](std::size_t offset, std::size_t length, bool vertex_attribute) {
    nlohmann::json view = {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", length}};
    // Instance attributes are read per instance, not as vertices: no target.
    if (vertex_attribute) view["target"] = kArrayBuffer;
    views.push_back(view);
    return views.size() - 1;
  };
  const auto add_accessor = [&](std::size_t view, std::uint64_t count, const nlohmann::json* min,
                                const nlohmann::json* max) {
    nlohmann::json a = {{"bufferView", view}, {"componentType", kFloat}, {"count", count}, {"type", "VEC3"}};
    if (min) a["min"] = *min;
    if (max) a["max"] = *max;
    accessors.push_back(a);
    return accessors.size() - 1;
  };
  std::vector<std::size_t> mesh_of(r.element_count());
  for (const std::uint8_t e : used) {
    const Shape& shape = r.shape(e);
    const std::size_t vertices = 3 * shape.triangles.size();
    // Positions, with their float extent (what a reader will see).
    glm::vec3 lo(std::numeric_limits<float>::max()), hi(std::numeric_limits<float>::lowest());
    const std::size_t positions_at = mesh_data.size();
    for (const Triangle& t : shape.triangles)
      for (const glm::dvec3& c : t.corners) {
        const glm::vec3 p(c);
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
        mesh_data.put_bytes(&p, sizeof p);
      }
    const std::size_t normals_at = mesh_data.size();
    glm::vec3 nlo(std::numeric_limits<float>::max()), nhi(std::numeric_limits<float>::lowest());
    for (const Triangle& t : shape.triangles)
      for (int c = 0; c < 3; ++c) {
        const glm::vec3 n(t.normal);
        nlo = glm::min(nlo, n);
        nhi = glm::max(nhi, n);
        mesh_data.put_bytes(&n, sizeof n);
      }
    const nlohmann::json pmin = float3_json(lo), pmax = float3_json(hi);
    const nlohmann::json nmin = float3_json(nlo), nmax = float3_json(nhi);
    const std::size_t position = add_accessor(add_view(positions_at, normals_at - positions_at, true), vertices, &pmin, &pmax);
    const std::size_t normal = add_accessor(add_view(normals_at, mesh_data.size() - normals_at, true), vertices, &nmin, &nmax);
    nlohmann::json primitive = nlohmann::json::object();
    primitive["attributes"] = {{"POSITION", position}, {"NORMAL", normal}};
    primitive["mode"] = 4;  // triangles
    mesh_of[e] = meshes.size();
    meshes.push_back({{"name", palette.elements[e].name}, {"primitives", nlohmann::json::array({primitive})}});
  }
  // Float data: every view so far starts and ends on a 4-byte boundary.
  std::uint64_t bin_size = mesh_data.size();
  for (const std::uint8_t e : used) {
    const Instances& in = instances[e];
    const nlohmann::json tmin = float3_json(r.corner(in.min.x, in.min.y, in.min.z));
    const nlohmann::json tmax = float3_json(r.corner(in.max.x, in.max.y, in.max.z));
    const std::uint64_t length = 12 * in.count;
    const std::size_t translation = add_accessor(add_view(bin_size, length, false), in.count, &tmin, &tmax);
    bin_size += length;
    nodes.push_back({{"name", palette.elements[e].name},
                     {"mesh", mesh_of[e]},
                     {"extensions", {{kInstancing, {{"attributes", {{"TRANSLATION", translation}}}}}}}});
  }

  // glTF forbids empty top-level arrays and zero-length buffers: an
  // all-empty reconstruction is just an empty scene.
  nlohmann::json gltf = {{"asset", {{"version", "2.0"}, {"generator", "voxd"}}}, {"scene", 0}};
  if (used.empty()) {
    gltf["scenes"] = nlohmann::json::array({nlohmann::json::object()});
  } else {
    // glTF is Y-up; the model's axes are CAD's Z-up. One root node turns
    // the whole model -90 degrees about x, (x, y, z) -> (x, z, -y), so
    // viewers stand the part up while the data keeps the model's
    // coordinates (what the voxels, the STL and the job's grid use).
    nlohmann::json children = nlohmann::json::array();
    for (std::size_t n = 0; n < nodes.size(); ++n) children.push_back(n);
    const double half = std::sqrt(0.5);
    nodes.push_back({{"name", "voxd model (Z-up model axes turned to glTF's Y-up)"},
                     {"rotation", {-half, 0.0, 0.0, half}},
                     {"children", children}});
    // Required, not only used: a viewer without instancing must refuse the
    // file rather than draw one element per node at the origin.
    gltf["extensionsUsed"] = nlohmann::json::array({kInstancing});
    gltf["extensionsRequired"] = nlohmann::json::array({kInstancing});
    gltf["scenes"] = nlohmann::json::array({{{"nodes", {nodes.size() - 1}}}});
    gltf["nodes"] = nodes;
    gltf["meshes"] = meshes;
    gltf["accessors"] = accessors;
    gltf["bufferViews"] = views;
    gltf["buffers"] = nlohmann::json::array({{{"byteLength", bin_size}}});
  }
  std::string json = gltf.dump();
  json.resize(padded4(json.size()), ' ');

  const std::uint64_t bin_chunk = used.empty() ? 0 : 8 + padded4(bin_size);
  const std::uint64_t total = 12 + 8 + json.size() + bin_chunk;
  if (total > std::numeric_limits<std::uint32_t>::max())
    throw Error(ErrorCode::limit_exceeded,
                "GLB writer: the file would take " + std::to_string(total) + " bytes, more than GLB's 4 GiB");

  ByteBuffer out;
  out.reset();
  put_u32(out, kGlbMagic);
  put_u32(out, 2);
  put_u32(out, static_cast<std::uint32_t>(total));
  put_u32(out, static_cast<std::uint32_t>(json.size()));
  put_u32(out, kChunkJson);
  out.put_bytes(json.data(), json.size());
  if (!used.empty()) {
    put_u32(out, static_cast<std::uint32_t>(padded4(bin_size)));
    put_u32(out, kChunkBin);
    out.put_bytes(mesh_data.data(), mesh_data.size());
    // Translations, element after element, in x-fastest voxel order.
    for (const std::uint8_t e : used) {
      for (std::size_t n = 0; n < voxels[e].size(); ++n) {
        const glm::u32vec3& v = voxels[e][n];
        put_float3(out, r.corner(v.x, v.y, v.z));
        if (n % 4096 == 4095) flush_if_large(out, sink);
      }
      flush_if_large(out, sink);
    }
    const std::uint8_t zeros[3] = {};
    out.put_bytes(zeros, padded4(bin_size) - bin_size);
  }
  sink.write(out.bytes());
}

}  // namespace voxd
