// Draco (.drc), Google's compressed mesh format, decoded by libdraco. The
// POSITION attribute's distinct values become the vertices, so the mesh keeps
// the indexing the encoder chose; points that differ only in other attributes
// (normals, texture coordinates) share a vertex.
#include <limits>
#include <memory>
#include <new>
#include <stdexcept>
#include <string>

#include <draco/compression/decode.h>

#include "mesh_io/decode_checks.h"
#include "mesh_io/draco_header.h"
#include "mesh_io/format_decoders.h"
#include "voxd/error.h"

namespace voxd::mesh_io {
namespace {

constexpr std::string_view kFormat = "Draco";

draco::DecoderBuffer make_buffer(std::span<const std::uint8_t> data) {
  draco::DecoderBuffer buffer;
  buffer.Init(reinterpret_cast<const char*>(data.data()), data.size());
  return buffer;
}

[[noreturn]] void throw_rejected(const draco::Status& status) {
  throw Error(ErrorCode::malformed_input,
              "the Draco decoder rejected the data (" + status.error_msg_string() + "); the file is corrupt or cut off");
}

std::unique_ptr<draco::Mesh> decode_draco_mesh(std::span<const std::uint8_t> data) {
  draco::DecoderBuffer probe = make_buffer(data);
  const auto type = draco::Decoder::GetEncodedGeometryType(&probe);
  if (!type.ok()) throw_rejected(type.status());
  if (type.value() == draco::POINT_CLOUD)
    throw Error(ErrorCode::no_usable_triangles,
                "the Draco file holds a point cloud, not a triangle mesh; voxelizing needs triangles");
  if (type.value() != draco::TRIANGULAR_MESH)
    throw Error(ErrorCode::malformed_input, "the Draco file holds neither a mesh nor a point cloud");
  draco::DecoderBuffer buffer = make_buffer(data);
  draco::Decoder decoder;
  try {
    auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
    if (!decoded.ok()) throw_rejected(decoded.status());
    return std::move(decoded).value();
  } catch (const std::bad_alloc&) {
    // libdraco sizes its buffers from counts in the stream.
    throw Error(ErrorCode::malformed_input,
                "decoding the Draco data needs more memory than the decoder may use: the file is corrupt, or "
                "larger than this service decodes (its --max-decode-memory)");
  } catch (const std::length_error&) {
    throw Error(ErrorCode::malformed_input,
                "the Draco data declares more elements than can be decoded; the file is corrupt");
  }
}

}  // namespace

Mesh decode_draco(std::span<const std::uint8_t> data, const DecodeLimits& limits) {
  check_draco_claims(read_draco_claims(data), data.size(), limits);
  if (limits.draco_decoder) return limits.draco_decoder(data);
  const std::unique_ptr<draco::Mesh> decoded = decode_draco_mesh(data);
  const draco::PointAttribute* position = decoded->GetNamedAttribute(draco::GeometryAttribute::POSITION);
  if (position == nullptr || position->size() == 0)
    throw Error(ErrorCode::malformed_input, "the Draco mesh has no vertex positions (no POSITION attribute)");
  // Positions are numbers; a bool (or invalid) attribute would be converted
  // by loading bytes as bool, which is undefined for values other than 0 and 1.
  if (position->data_type() == draco::DT_BOOL || position->data_type() == draco::DT_INVALID ||
      position->data_type() >= draco::DT_TYPES_COUNT || position->num_components() < 1)
    throw Error(ErrorCode::malformed_input,
                "the Draco POSITION attribute is not numeric (data type " +
                    std::to_string(static_cast<int>(position->data_type())) + "); the file is corrupt");
  check_triangle_limit(decoded->num_faces(), limits, kFormat);
  if (position->size() > std::numeric_limits<std::uint32_t>::max())
    throw Error(ErrorCode::limit_exceeded, "the Draco mesh has more than 4294967295 vertices");

  Mesh mesh;
  mesh.vertices.resize(position->size());
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    // Positions with fewer than 3 components (2D meshes) are padded with 0.
    float xyz[3] = {0.0f, 0.0f, 0.0f};
    if (!position->ConvertValue<float, 3>(draco::AttributeValueIndex(static_cast<std::uint32_t>(i)), xyz))
      throw Error(ErrorCode::malformed_input, "the Draco position of vertex " + std::to_string(i) + " cannot be read");
    mesh.vertices[i] = {xyz[0], xyz[1], xyz[2]};
    if (!is_finite(mesh.vertices[i])) throw_non_finite(kFormat, "vertex " + std::to_string(i));
  }

  const std::uint32_t points = decoded->num_points();
  mesh.triangles.resize(decoded->num_faces());
  for (std::uint32_t f = 0; f < decoded->num_faces(); ++f) {
    const draco::Mesh::Face& face = decoded->face(draco::FaceIndex(f));
    for (int c = 0; c < 3; ++c) {
      const draco::PointIndex point = face[c];
      // mapped_index() does not check its argument.
      const bool in_range = point.value() < points && (position->is_mapping_identity() ||
                                                       point.value() < position->indices_map_size());
      const std::uint32_t value = in_range ? position->mapped_index(point).value() : 0;
      if (!in_range || value >= mesh.vertices.size())
        throw Error(ErrorCode::malformed_input, "the Draco face " + std::to_string(f) +
                                                    " refers to a point outside the mesh; the file is corrupt");
      mesh.triangles[f][c] = value;
    }
  }
  keep_usable_triangles(mesh, kFormat);
  return mesh;
}

}  // namespace voxd::mesh_io
