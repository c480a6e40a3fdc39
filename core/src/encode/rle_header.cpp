// The preamble and JSON header of the RLE stream. JSON keeps the header
// extensible (new optional keys, free metadata) while the binary preamble lets
// a reader recognise the stream and its version from the first 8 bytes.
#include <cmath>
#include <string>

#include <nlohmann/json.hpp>

#include "encode/rle_stream.h"
#include "voxd/error.h"

namespace voxd::encode {
namespace {

void append_u32le(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}

[[noreturn]] void bad_header(const std::string& message) {
  throw Error(ErrorCode::malformed_input, "RLE stream header: " + message);
}

const nlohmann::json& required(const nlohmann::json& header, const char* key) {
  const auto it = header.find(key);
  if (it == header.end()) bad_header(std::string("missing required key \"") + key + "\"");
  return *it;
}

const nlohmann::json& array_of_3(const nlohmann::json& header, const char* key) {
  const nlohmann::json& v = required(header, key);
  if (!v.is_array() || v.size() != 3) bad_header(std::string("\"") + key + "\" must be an array of 3 numbers");
  return v;
}

double finite_number(const nlohmann::json& v, const std::string& what) {
  if (!v.is_number()) bad_header(what + " must be a number");
  const double d = v.get<double>();
  if (!std::isfinite(d)) bad_header(what + " must be finite");
  return d;
}

Grid parse_grid(const nlohmann::json& header) {
  Grid grid;
  const nlohmann::json& dims = array_of_3(header, "dims");
  for (int a = 0; a < 3; ++a) {
    const nlohmann::json& d = dims[static_cast<std::size_t>(a)];
    // Integers only: "3.0" or "-3" are errors, not silently converted.
    if (!d.is_number_unsigned() || d.get<std::uint64_t>() < 1 ||
        d.get<std::uint64_t>() > static_cast<std::uint64_t>(kMaxGridDim))
      bad_header("dims[" + std::to_string(a) + "] must be an integer between 1 and " + std::to_string(kMaxGridDim) +
                 ", found " + d.dump());
    grid.dims[a] = static_cast<std::int64_t>(d.get<std::uint64_t>());
  }
  const nlohmann::json& origin = array_of_3(header, "origin");
  for (int a = 0; a < 3; ++a)
    grid.origin[a] = finite_number(origin[static_cast<std::size_t>(a)], "origin[" + std::to_string(a) + "]");
  grid.voxel_size = finite_number(required(header, "voxel_size"), "voxel_size");
  if (!(grid.voxel_size > 0.0)) bad_header("voxel_size must be positive");
  return grid;
}

}  // namespace

std::vector<std::uint8_t> encode_rle_header(const Grid& grid, RleValueType value_type, const std::string& metadata_json) {
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(grid.origin[a]))
      throw Error(ErrorCode::invalid_argument, "RLE writer: the grid origin must be finite");
    if (grid.dims[a] < 1) throw Error(ErrorCode::invalid_argument, "RLE writer: the grid has no voxels");
  }
  if (!std::isfinite(grid.voxel_size) || !(grid.voxel_size > 0.0))
    throw Error(ErrorCode::invalid_argument, "RLE writer: voxel_size must be positive and finite");

  // ordered_json keeps the keys in the order of the specification, which
  // makes the header easy to read in a hex dump.
  nlohmann::ordered_json header;
  header["dims"] = {grid.dims.x, grid.dims.y, grid.dims.z};
  header["origin"] = {grid.origin.x, grid.origin.y, grid.origin.z};
  header["voxel_size"] = grid.voxel_size;
  header["axis_order"] = "xyz";
  header["value_type"] = to_string(value_type);
  if (!metadata_json.empty()) header["metadata"] = nlohmann::ordered_json::parse(metadata_json);
  const std::string text = header.dump();

  std::vector<std::uint8_t> out(kRleMagic.begin(), kRleMagic.end());
  out.push_back(kRleVersion);
  append_u32le(out, static_cast<std::uint32_t>(text.size()));
  out.insert(out.end(), text.begin(), text.end());
  return out;
}

RleHeader read_rle_header(ByteCursor& in) {
  // Compare the magic byte by byte so that a short prefix of it reads as a
  // truncated stream and anything else as "not an RLE stream".
  for (char expected : kRleMagic) {
    if (in.u8("the 'VOXDRLE' magic") != static_cast<std::uint8_t>(expected))
      in.fail(ErrorCode::malformed_input, "not a voxd RLE stream (it does not start with \"VOXDRLE\")");
  }
  const std::uint8_t version = in.u8("the format version byte");
  if (version != kRleVersion)
    in.fail(ErrorCode::malformed_input, "format version " + std::to_string(version) +
                                            " is not supported (this reader reads version " +
                                            std::to_string(kRleVersion) + ")");
  const std::uint32_t length = in.u32le("the header length");
  if (length > kMaxRleHeaderBytes)
    in.fail(ErrorCode::malformed_input, "header length " + std::to_string(length) + " exceeds the limit of " +
                                            std::to_string(kMaxRleHeaderBytes) + " bytes");
  const auto text = in.bytes(length, "the JSON header");

  nlohmann::json header;
  try {
    header = nlohmann::json::parse(text.begin(), text.end());
  } catch (const nlohmann::json::exception& e) {
    bad_header(std::string("not valid JSON: ") + e.what());
  }
  if (!header.is_object()) bad_header("must be a JSON object");

  RleHeader result;
  result.grid = parse_grid(header);
  const nlohmann::json& axis_order = required(header, "axis_order");
  if (axis_order != "xyz")
    bad_header("axis_order must be \"xyz\" (the only order of format version 1), found " + axis_order.dump());
  const nlohmann::json& value_type = required(header, "value_type");
  const auto type = value_type.is_string() ? value_named(kRleValueTypeNames, value_type.get<std::string>()) : std::nullopt;
  if (!type)
    bad_header("value_type must be one of \"bit\", \"u8\", \"u16\", \"f32\", \"rgba8\", found " + value_type.dump());
  result.value_type = *type;
  if (const auto it = header.find("metadata"); it != header.end()) {
    if (!it->is_object()) bad_header("metadata must be a JSON object");
    result.metadata_json = it->dump();
  }
  return result;
}

}  // namespace voxd::encode
