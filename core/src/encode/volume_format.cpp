// Format names, file extensions and media types, and the encoder dispatch.
#include "voxd/volume_format.h"

#include <algorithm>
#include <cctype>
#include <string>

#include "voxd/error.h"

namespace voxd {
namespace {

constexpr VolumeFormat kAllFormats[] = {VolumeFormat::rle, VolumeFormat::binvox, VolumeFormat::raw};

bool equals_ignoring_case(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) == std::tolower(static_cast<unsigned char>(y));
         });
}

}  // namespace

const char* to_string(VolumeFormat format) noexcept {
  switch (format) {
    case VolumeFormat::rle: return "rle";
    case VolumeFormat::binvox: return "binvox";
    case VolumeFormat::raw: return "raw";
  }
  return "unknown";
}

std::optional<VolumeFormat> volume_format_from_string(std::string_view name) {
  for (VolumeFormat f : kAllFormats)
    if (name == to_string(f)) return f;
  return std::nullopt;
}

const char* file_extension(VolumeFormat format) noexcept {
  switch (format) {
    case VolumeFormat::rle: return ".rle";
    case VolumeFormat::binvox: return ".binvox";
    case VolumeFormat::raw: return ".raw";
  }
  return "";
}

std::optional<VolumeFormat> volume_format_from_path(std::string_view path) {
  // Extensions compare case-insensitively: "MODEL.BINVOX" is still binvox.
  for (VolumeFormat f : kAllFormats) {
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
  }
  return "application/octet-stream";
}

void encode_volume(const BitVolume& volume, VolumeFormat format, ByteSink& sink, const EncodeOptions& options) {
  switch (format) {
    case VolumeFormat::rle: return write_rle(volume, sink);
    case VolumeFormat::binvox: return write_binvox(volume, sink);
    case VolumeFormat::raw: return write_raw(volume, options.raw_packing, sink);
  }
  throw Error(ErrorCode::invalid_argument, "unknown volume format");
}

}  // namespace voxd
