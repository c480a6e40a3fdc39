#pragma once
// Constants and header of voxd's RLE stream (proto-schemas/rle-format.md),
// shared by the writer and the reader.
//
//   preamble   "VOXDRLE" + version byte (1)
//   header     u32 little-endian length N, then N bytes of UTF-8 JSON
//   slab block 'S', varint k, varint payload length, payload   (k = 0..nz-1)
//   end block  'E', varint slab count
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "encode/byte_cursor.h"
#include "voxd/grid.h"
#include "voxd/bit_volume.h"
#include "voxd/run_slab.h"
#include "voxd/byte_sink.h"
#include "voxd/encode/volume_format.h"
#include "voxd/enum_names.h"

namespace voxd::encode {

inline constexpr std::string_view kRleMagic = "VOXDRLE";
inline constexpr std::uint8_t kRleVersion = 1;
inline constexpr std::uint8_t kSlabTag = 'S';
inline constexpr std::uint8_t kEndTag = 'E';
// Readers refuse longer JSON headers: nothing legitimate comes near it and
// it bounds what a lying length can make us parse.
inline constexpr std::uint32_t kMaxRleHeaderBytes = 1u << 20;

enum class RleValueType { bit, u8, u16, f32, rgba8 };

inline constexpr EnumNames<RleValueType, 5> kRleValueTypeNames{{
    {RleValueType::bit, "bit"}, {RleValueType::u8, "u8"}, {RleValueType::u16, "u16"}, {RleValueType::f32, "f32"},
    {RleValueType::rgba8, "rgba8"}}};
inline const char* to_string(RleValueType type) noexcept { return name_of(kRleValueTypeNames, type); }

struct RleHeader {
  Grid grid;
  RleValueType value_type = RleValueType::bit;
  std::string metadata_json;  // the "metadata" object's text, empty when absent
};

// Preamble + length-prefixed JSON header, with `metadata_json` (a JSON
// object's text) under "metadata" when not empty. Throws
// Error(invalid_argument) for a grid JSON cannot carry (non-finite numbers,
// non-positive sizes).
std::vector<std::uint8_t> encode_rle_header(const Grid& grid, RleValueType value_type,
                                            const std::string& metadata_json = {});

// Reads and validates the preamble and JSON header, leaving `in` at the first
// block. Throws Error(malformed_input / truncated_input).
RleHeader read_rle_header(ByteCursor& in);

// A bit volume's RLE written as its z layers arrive (streamed voxelization):
// the header, then each slab's layers (global indices from k0), then the end
// block after the last of the grid's nz layers. Byte for byte write_rle's.
void write_rle_bit_header(const Grid& grid, ByteSink& sink);
void write_rle_bit_layers(const BitVolume& slab, std::int64_t k0, ByteSink& sink);
void write_rle_bit_layers(const RunSlab& slab, std::int64_t k0, ByteSink& sink);
// The blocks write_rle_bit_layers writes for `slab` at k0, into `out`.
void encode_rle_bit_layers(const RunSlab& slab, std::int64_t k0, std::vector<std::uint8_t>& out);
void write_rle_end(std::int64_t nz, ByteSink& sink);
// The same for a volume of values (u8, f32 or rgba8: `slab`'s type).
void write_rle_value_header(const ValueVolume& type, const Grid& grid, ByteSink& sink);
void write_rle_value_layers(const ValueVolume& slab, std::int64_t k0, ByteSink& sink);

}  // namespace voxd::encode
