#pragma once
// Volume encoders and decoders. Encoders stream slab by slab into a ByteSink
// and never copy the whole volume. Large volumes are encoded on worker
// threads, but the sink is only ever called on the calling thread, in order.
// Formats:
//  - rle:    voxd's run-length stream (proto-schemas/rle-format.md)
//  - binvox: Patrick Min's binvox (cubic; non-cubic grids padded with empty voxels).
//            Bit volumes are written as "#binvox 1" (values 0/1); u8 volumes as
//            "#binvox 2", the version whose set voxels carry a value 1..255.
//  - raw:    headerless, x fastest then y then z; one byte per voxel (0/1) or
//            packed bits (LSB first, no row padding); u8 and little-endian
//            float32 values as they are
//  - nrrd:   NRRD 0004 (ParaView, 3D Slicer, ITK): a text header placing the
//            voxel centres in model space, then the raw data, uncompressed or
//            gzip; bits as uchar 0/1, u8 as uchar, f32 as float
//  - vox:       MagicaVoxel (voxd/encode/magica_vox.h), colour volumes only
//  - png-stack: a ZIP of one RGBA PNG per z layer (voxd/encode/png_stack.h), colour volumes only
//  - stl, glb:  a palette job's reconstruction as a mesh (voxd/encode/palette_export.h);
//               they need the palette, so encode_volume refuses them and the
//               caller writes them
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <variant>

#include "voxd/bit_volume.h"
#include "voxd/byte_sink.h"
#include "voxd/dense_volume.h"
#include "voxd/enum_names.h"

namespace voxd {

enum class VolumeFormat { rle, binvox, raw, nrrd, vox, png_stack, stl, glb, ply };
inline constexpr EnumNames<VolumeFormat, 9> kVolumeFormatNames{{
    {VolumeFormat::rle, "rle"}, {VolumeFormat::binvox, "binvox"}, {VolumeFormat::raw, "raw"},
    {VolumeFormat::nrrd, "nrrd"}, {VolumeFormat::vox, "vox"}, {VolumeFormat::png_stack, "png-stack"},
    {VolumeFormat::stl, "stl"}, {VolumeFormat::glb, "glb"}, {VolumeFormat::ply, "ply"}}};
enum class RawPacking { bytes, bits };
enum class NrrdEncoding { raw, gzip };

inline const char* to_string(VolumeFormat format) noexcept { return name_of(kVolumeFormatNames, format); }
// "rle, binvox, ... or glb", for messages.
inline std::string volume_format_choices() { return names_joined(kVolumeFormatNames, ", ", " or "); }
inline std::optional<VolumeFormat> volume_format_from_string(std::string_view name) {
  return value_named(kVolumeFormatNames, name);
}
// From a path's extension (.rle, .binvox, .raw, .nrrd); nullopt if unrecognised.
std::optional<VolumeFormat> volume_format_from_path(std::string_view path);
// MIME type used when serving the format.
const char* media_type(VolumeFormat format) noexcept;
// File extension with the dot (".rle", ".binvox", ".raw", ".nrrd", ".vox",
// ".zip" for png-stack, ".stl", ".glb", ".ply").
const char* file_extension(VolumeFormat format) noexcept;

// Float values in RLE as integer levels (far smaller than f32 runs inside a
// distance band): see write_rle_quantized.
enum class Quantize { none, u8, u16 };

struct EncodeOptions {
  RawPacking raw_packing = RawPacking::bytes;
  NrrdEncoding nrrd_encoding = NrrdEncoding::raw;
  std::string content = "voxels";      // what the values are: NRRD "content:", quantized RLE metadata
  Quantize quantize = Quantize::none;   // rle of f32 values only
};

// A volume of one value per voxel: coverage bytes or fractions, distances,
// palette element indices, slice colours.
using ValueVolume = std::variant<DenseVolume<std::uint8_t>, DenseVolume<float>, DenseVolume<Rgba8>>;
const Grid& grid_of(const ValueVolume& volume);
// "u8", "f32" or "rgba8", the RLE value type names.
const char* value_type_name(const ValueVolume& volume);
std::size_t byte_size(const ValueVolume& volume);

void encode_volume(const BitVolume& volume, VolumeFormat format, ByteSink& sink,
                   const EncodeOptions& options = {});
// u8: rle, binvox (version 2), raw, nrrd. f32: rle, raw, nrrd. rgba8: rle,
// raw (4 bytes a voxel: r, g, b, a), vox, png-stack. Throws
// Error(invalid_argument) with format_refusal's message otherwise.
void encode_volume(const ValueVolume& volume, VolumeFormat format, ByteSink& sink,
                   const EncodeOptions& options = {});
// Why `format` (with `options`) cannot hold `volume`, said so a user can pick
// another; nullopt when it can. Lets a server refuse before streaming.
std::optional<std::string> format_refusal(const ValueVolume& volume, VolumeFormat format, const EncodeOptions& options);
// The same for a bit volume: vox, png-stack, stl and glb are refused.
std::optional<std::string> format_refusal(const BitVolume& volume, VolumeFormat format);

void write_rle(const BitVolume& volume, ByteSink& sink);
void write_rle(const DenseVolume<std::uint8_t>& volume, ByteSink& sink);
void write_binvox(const BitVolume& volume, ByteSink& sink);
void write_binvox(const DenseVolume<std::uint8_t>& volume, ByteSink& sink);
void write_raw(const BitVolume& volume, RawPacking packing, ByteSink& sink);
void write_raw(const DenseVolume<std::uint8_t>& volume, ByteSink& sink);
void write_nrrd(const BitVolume& volume, std::string_view content, ByteSink& sink,
                NrrdEncoding encoding = NrrdEncoding::raw);
void write_nrrd(const DenseVolume<std::uint8_t>& volume, std::string_view content, ByteSink& sink,
                NrrdEncoding encoding = NrrdEncoding::raw);

// Float volumes (distances, local thickness): voxd RLE with value_type f32,
// raw little-endian float32 (x fastest, then y, then z), and NRRD (a text
// header then the raw data; opens in ParaView, 3D Slicer, ITK), whose header
// places voxel centres in model space and names the quantity in `content`.
void write_rle(const DenseVolume<float>& volume, ByteSink& sink);
// Float values as RLE u8 or u16 levels q with value = offset + scale * q
// (proto-schemas/rle-format.md 3.1), offset and scale in the header's
// "metadata": {"quantization": {"offset", "scale", "levels", "content"}}.
// Levels 0 .. L = 2^bits - 2 span [lo, hi]: the finite values' range, made
// symmetric (lo = -hi) when it has both signs, so that 0 is level L / 2
// exactly (a distance field's surface stays where it is) and the error is
// at most scale / 2. NaN becomes level L + 1 (the one level left over);
// infinities clamp to the ends. Quantized slab by slab: no copy of the
// volume. Throws Error(invalid_argument) for Quantize::none.
void write_rle_quantized(const DenseVolume<float>& volume, Quantize levels, std::string_view content, ByteSink& sink);
// Float volumes' raw and NRRD writers write each value times `scale` (a
// unit's: voxels to model units), a slab at a time.
void write_raw(const DenseVolume<float>& volume, ByteSink& sink, float scale = 1.0f);
void write_raw(const DenseVolume<Rgba8>& volume, ByteSink& sink);
// Colour volumes (slice voxelization, voxd/voxelize/slice_functions.h): voxd RLE with
// value_type rgba8, runs of equal colours (all four bytes r, g, b, a equal).
void write_rle(const DenseVolume<Rgba8>& volume, ByteSink& sink);
void write_nrrd(const DenseVolume<float>& volume, std::string_view content, ByteSink& sink,
                NrrdEncoding encoding = NrrdEncoding::raw, float scale = 1.0f);

// What a reader may allocate for the decoded volume. Readers validate the
// whole input before allocating, so a lying header cannot make them allocate;
// this bounds what a valid but huge input may cost (Error(limit_exceeded)).
struct ReadLimits {
  std::uint64_t max_volume_bytes = std::uint64_t{1} << 30;
};

// Readers (round trips, tests, CLI conversions). Throw Error(malformed_input /
// truncated_input) on bad data.
BitVolume read_rle_bits(std::span<const std::uint8_t> data, const ReadLimits& limits = {});
DenseVolume<std::uint8_t> read_rle_u8(std::span<const std::uint8_t> data, const ReadLimits& limits = {});
DenseVolume<float> read_rle_f32(std::span<const std::uint8_t> data, const ReadLimits& limits = {});
DenseVolume<std::uint16_t> read_rle_u16(std::span<const std::uint8_t> data, const ReadLimits& limits = {});
DenseVolume<Rgba8> read_rle_rgba8(std::span<const std::uint8_t> data, const ReadLimits& limits = {});
// The header's "metadata" object as JSON text ("" when it has none), e.g. to
// read a quantized stream's offset and scale.
std::string read_rle_metadata(std::span<const std::uint8_t> data);
// binvox has no voxel size/origin beyond translate/scale; the returned grid is
// the cubic D^3 grid with origin = translate and voxel_size = scale / D.
// Reads versions 1 and 2; read_binvox sets the voxels whose value is non-zero.
BitVolume read_binvox(std::span<const std::uint8_t> data, const ReadLimits& limits = {});
DenseVolume<std::uint8_t> read_binvox_u8(std::span<const std::uint8_t> data, const ReadLimits& limits = {});
// `grid` gives the dims (Error(invalid_argument) if out of range); the data
// must be exactly the size they imply. Bytes must be 0 or 1; bits past the
// last voxel in the last byte must be 0.
BitVolume read_raw(std::span<const std::uint8_t> data, const Grid& grid, RawPacking packing,
                   const ReadLimits& limits = {});

}  // namespace voxd
