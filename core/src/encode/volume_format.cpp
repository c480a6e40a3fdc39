// Format names, file extensions and media types, and the encoder dispatch.
#include "voxd/encode/volume_format.h"

#include <algorithm>
#include <cctype>
#include <string>
#include <type_traits>

#include "voxd/error.h"
#include "voxd/encode/magica_vox.h"
#include "voxd/encode/png_stack.h"

namespace voxd {
namespace {

// Formats that hold a mesh of the result, not its voxels: a palette job's
// reconstruction, a solid's voxel surface, an sdf's zero level set (each
// made by its own writer: voxd/encode/palette_export.h, volume_surface.h).
bool mesh_format(VolumeFormat f) { return f == VolumeFormat::stl || f == VolumeFormat::glb || f == VolumeFormat::ply; }
bool colour_only(VolumeFormat f) { return f == VolumeFormat::vox || f == VolumeFormat::png_stack; }

bool equals_ignoring_case(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) == std::tolower(static_cast<unsigned char>(y));
         });
}

}  // namespace

const char* file_extension(VolumeFormat format) noexcept {
  switch (format) {
    case VolumeFormat::rle: return ".rle";
    case VolumeFormat::binvox: return ".binvox";
    case VolumeFormat::raw: return ".raw";
    case VolumeFormat::nrrd: return ".nrrd";
    case VolumeFormat::vox: return ".vox";
    case VolumeFormat::png_stack: return ".zip";
    case VolumeFormat::stl: return ".stl";
    case VolumeFormat::glb: return ".glb";
    case VolumeFormat::ply: return ".ply";
  }
  return "";
}

std::optional<VolumeFormat> volume_format_from_path(std::string_view path) {
  // Extensions compare case-insensitively: "MODEL.BINVOX" is still binvox.
  for (const auto& [f, name] : kVolumeFormatNames) {
    const std::string_view ext = file_extension(f);
    if (path.size() > ext.size() && equals_ignoring_case(path.substr(path.size() - ext.size()), ext)) return f;
  }
  return std::nullopt;
}

const char* media_type(VolumeFormat format) noexcept {
  switch (format) {
    case VolumeFormat::rle: return "application/vnd.voxd.rle";
    case VolumeFormat::binvox: return "application/x-binvox";
    case VolumeFormat::raw: return "application/octet-stream";
    case VolumeFormat::nrrd: return "application/x-nrrd";
    case VolumeFormat::vox: return "application/octet-stream";
    case VolumeFormat::png_stack: return "application/zip";
    case VolumeFormat::stl: return "model/stl";
    case VolumeFormat::glb: return "model/gltf-binary";
    case VolumeFormat::ply: return "application/x-ply";
  }
  return "application/octet-stream";
}

std::optional<std::string> format_refusal(const BitVolume&, VolumeFormat format) {
  if (colour_only(format))
    return std::string(to_string(format)) + " holds colours (a slice job's result), not bits; ask for rle, binvox, raw or nrrd";
  if (mesh_format(format))
    return std::string(to_string(format)) +
           " is a mesh of the result (a solid's voxel surface, made from the volume by its own writer), not a volume "
           "format; ask for rle, binvox, raw or nrrd";
  return std::nullopt;
}

void encode_volume(const BitVolume& volume, VolumeFormat format, ByteSink& sink, const EncodeOptions& options) {
  if (auto refusal = format_refusal(volume, format)) throw Error(ErrorCode::invalid_argument, *refusal);
  switch (format) {
    case VolumeFormat::rle: return write_rle(volume, sink);
    case VolumeFormat::binvox: return write_binvox(volume, sink);
    case VolumeFormat::raw: return write_raw(volume, options.raw_packing, sink);
    case VolumeFormat::nrrd: return write_nrrd(volume, options.content, sink, options.nrrd_encoding);
    default: break;
  }
  throw Error(ErrorCode::invalid_argument, "unknown volume format");
}

const Grid& grid_of(const ValueVolume& volume) {
  return std::visit([](const auto& v) -> const Grid& { return v.grid(); }, volume);
}

const char* value_type_name(const ValueVolume& volume) {
  if (std::holds_alternative<DenseVolume<float>>(volume)) return "f32";
  if (std::holds_alternative<DenseVolume<Rgba8>>(volume)) return "rgba8";
  return "u8";
}

std::size_t byte_size(const ValueVolume& volume) {
  return std::visit([](const auto& v) { return v.values().size() * sizeof(v.values()[0]); }, volume);
}

std::optional<std::string> format_refusal(const ValueVolume& volume, VolumeFormat format, const EncodeOptions& options) {
  const bool floats = std::holds_alternative<DenseVolume<float>>(volume);
  const bool colours = std::holds_alternative<DenseVolume<Rgba8>>(volume);
  if (colours && (format == VolumeFormat::binvox || format == VolumeFormat::nrrd))
    return std::string(to_string(format)) + " does not hold the rgba8 colours of this volume; ask for rle, raw, vox or png-stack";
  if (!colours && colour_only(format))
    return std::string(to_string(format)) + " holds colours (a slice job's result), not the " + value_type_name(volume) +
           " values of this volume; ask for rle, raw or nrrd";
  if (mesh_format(format))
    return std::string(to_string(format)) +
           " is a mesh of the result (a palette job's reconstruction or an sdf's zero level set, each made by its own "
           "writer), not a volume format; ask for rle, raw or nrrd";
  if (format == VolumeFormat::binvox && floats)
    return "binvox holds bits or bytes, not the float32 values of this volume; ask for rle, raw or nrrd";
  if (options.quantize != Quantize::none && (format != VolumeFormat::rle || !floats))
    return std::string("quantize turns float32 values into rle levels; ") +
           (floats ? "ask for format rle" : "this volume holds " + std::string(value_type_name(volume)) + " values already");
  if (format == VolumeFormat::raw && options.raw_packing == RawPacking::bits)
    return std::string("raw packing bits holds one bit per voxel, not the ") + value_type_name(volume) +
           " values of this volume; ask for packing bytes";
  return std::nullopt;
}

void encode_volume(const ValueVolume& volume, VolumeFormat format, ByteSink& sink, const EncodeOptions& options) {
  if (auto refusal = format_refusal(volume, format, options)) throw Error(ErrorCode::invalid_argument, *refusal);
  std::visit(
      [&](const auto& v) {
        using V = std::decay_t<decltype(v)>;
        switch (format) {
          case VolumeFormat::rle:
            if constexpr (std::is_same_v<V, DenseVolume<float>>)
              if (options.quantize != Quantize::none) return write_rle_quantized(v, options.quantize, options.content, sink);
            return write_rle(v, sink);
          case VolumeFormat::binvox:
            if constexpr (std::is_same_v<V, DenseVolume<std::uint8_t>>) return write_binvox(v, sink);
            break;
          case VolumeFormat::raw: return write_raw(v, sink);
          case VolumeFormat::nrrd:
            if constexpr (!std::is_same_v<V, DenseVolume<Rgba8>>) return write_nrrd(v, options.content, sink, options.nrrd_encoding);
            break;
          case VolumeFormat::vox:
            if constexpr (std::is_same_v<V, DenseVolume<Rgba8>>) return write_vox(v, sink);
            break;
          case VolumeFormat::png_stack:
            if constexpr (std::is_same_v<V, DenseVolume<Rgba8>>) return write_png_stack_zip(v, sink);
            break;
          case VolumeFormat::stl:
          case VolumeFormat::glb:
          case VolumeFormat::ply: break;
        }
        throw Error(ErrorCode::invalid_argument, "unknown volume format");
      },
      volume);
}

}  // namespace voxd
