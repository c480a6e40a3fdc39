// Volume encoders and decoders: round trips of every format, exact bytes
// against the specification, errors on truncated / corrupted input, a
// mutation loop, and independent Python readers (tests/tools/) written from
// the format descriptions alone.
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <sstream>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "support/test_meshes.h"
#include "voxd/error.h"
#include "voxd/encode/rle_slabs.h"
#include "voxd/encode/volume_format.h"

namespace voxd {
namespace {

using Bytes = std::vector<std::uint8_t>;

using test::make_grid;

BitVolume random_volume(const Grid& grid, std::uint32_t seed, double density = 0.5) {
  BitVolume v(grid);
  std::mt19937 rng(seed);
  std::bernoulli_distribution fill(density);
  for (std::int64_t k = 0; k < grid.dims.z; ++k)
    for (std::int64_t j = 0; j < grid.dims.y; ++j)
      for (std::int64_t i = 0; i < grid.dims.x; ++i)
        if (fill(rng)) v.set(i, j, k, true);
  return v;
}

// Random bits of density 1/8 filled a word at a time: fast enough for the
// volumes that exercise the parallel paths, also under the sanitizers.
BitVolume random_words_volume(const Grid& grid, std::uint64_t seed) {
  BitVolume v(grid);
  std::mt19937_64 rng(seed);
  const std::int64_t tail = grid.dims.x % 64;
  for (std::int64_t k = 0; k < grid.dims.z; ++k)
    for (std::int64_t j = 0; j < grid.dims.y; ++j)
      for (std::int64_t w = 0; w < v.row_words(); ++w) {
        std::uint64_t bits = rng() & rng() & rng();
        if (tail != 0 && w == v.row_words() - 1) bits &= (std::uint64_t{1} << tail) - 1;
        v.row(j, k)[w] = bits;
      }
  return v;
}

BitVolume full_volume(const Grid& grid) {
  BitVolume v(grid);
  for (std::int64_t k = 0; k < grid.dims.z; ++k)
    for (std::int64_t j = 0; j < grid.dims.y; ++j)
      for (std::int64_t i = 0; i < grid.dims.x; ++i) v.set(i, j, k, true);
  return v;
}

BitVolume sphere_volume(const Grid& grid) {
  BitVolume v(grid);
  const glm::dvec3 c = glm::dvec3(grid.dims) * 0.5;
  const double r = 0.45 * static_cast<double>(std::min({grid.dims.x, grid.dims.y, grid.dims.z}));
  for (std::int64_t k = 0; k < grid.dims.z; ++k)
    for (std::int64_t j = 0; j < grid.dims.y; ++j)
      for (std::int64_t i = 0; i < grid.dims.x; ++i) {
        const glm::dvec3 p = glm::dvec3(i + 0.5, j + 0.5, k + 0.5) - c;
        if (p.x * p.x + p.y * p.y + p.z * p.z <= r * r) v.set(i, j, k, true);
      }
  return v;
}

DenseVolume<std::uint8_t> random_u8_volume(const Grid& grid, std::uint32_t seed) {
  DenseVolume<std::uint8_t> v(grid);
  std::mt19937 rng(seed);
  // Mostly long runs of a few values, with some noise: exercises both the
  // run merging and the 8-byte run scan.
  std::uint8_t value = 0;
  for (auto& x : v.values()) {
    if (rng() % 13 == 0) value = static_cast<std::uint8_t>(rng() % 4 == 0 ? 0 : rng());
    x = rng() % 17 == 0 ? static_cast<std::uint8_t>(rng()) : value;
  }
  return v;
}

// Named test volumes: random, empty, full, dims that are not multiples of 64,
// non-cubic, single voxel, rows longer than one word.
struct NamedVolume {
  std::string name;
  BitVolume volume;
};

std::vector<NamedVolume> test_volumes() {
  std::vector<NamedVolume> out;
  out.push_back({"random 40x30x20", random_volume(make_grid({40, 30, 20}, {-1.25, 2.0, 1e-3}, 0.1), 1)});
  out.push_back({"sparse 130x7x9", random_volume(make_grid({130, 7, 9}, {0, 0, 0}, 2.5), 2, 0.02)});
  out.push_back({"dense 67x5x3", random_volume(make_grid({67, 5, 3}, {3, -4, 5}, 0.3), 3, 0.9)});
  out.push_back({"empty 67x5x3", BitVolume(make_grid({67, 5, 3}))});
  out.push_back({"full 67x5x3", full_volume(make_grid({67, 5, 3}, {1, 1, 1}, 0.5))});
  out.push_back({"full 64x64x2", full_volume(make_grid({64, 64, 2}))});
  out.push_back({"single voxel", full_volume(make_grid({1, 1, 1}, {7, 8, 9}, 0.125))});
  out.push_back({"sphere 70x70x70", sphere_volume(make_grid({70, 70, 70}, {-35, -35, -35}, 1.0))});
  out.push_back({"non-cubic 20x33x7", random_volume(make_grid({20, 33, 7}, {0.5, 0.25, -3}, 0.2), 4)});
  out.push_back({"tall 3x2x150", random_volume(make_grid({3, 2, 150}), 5)});
  out.push_back({"wide 200x1x1", random_volume(make_grid({200, 1, 1}), 6)});
  return out;
}

Bytes encode(const BitVolume& v, VolumeFormat format, RawPacking packing = RawPacking::bytes) {
  VectorSink sink;
  EncodeOptions options;
  options.raw_packing = packing;
  encode_volume(v, format, sink, options);
  return std::move(sink.data);
}

Bytes rle_u8(const DenseVolume<std::uint8_t>& v) {
  VectorSink sink;
  write_rle(v, sink);
  return std::move(sink.data);
}

Bytes binvox_u8(const DenseVolume<std::uint8_t>& v) {
  VectorSink sink;
  write_binvox(v, sink);
  return std::move(sink.data);
}

// Compares voxel by voxel, with `expected` possibly smaller than `actual`
// (binvox padding): voxels outside `expected` must be empty.
void expect_same_voxels(const BitVolume& expected, const BitVolume& actual) {
  const glm::i64vec3 e = expected.grid().dims;
  const glm::i64vec3 a = actual.grid().dims;
  ASSERT_TRUE(a.x >= e.x && a.y >= e.y && a.z >= e.z);
  std::int64_t mismatches = 0;
  for (std::int64_t k = 0; k < a.z; ++k)
    for (std::int64_t j = 0; j < a.y; ++j)
      for (std::int64_t i = 0; i < a.x; ++i) {
        const bool want = i < e.x && j < e.y && k < e.z && expected.get(i, j, k);
        if (actual.get(i, j, k) != want && ++mismatches <= 5)
          ADD_FAILURE() << "voxel (" << i << "," << j << "," << k << ") is " << !want << ", expected " << want;
      }
  EXPECT_EQ(mismatches, 0);
  // The reader must keep the row padding bits zero (BitVolume's invariant).
  if (actual.grid().dims.x % 64 != 0) {
    for (std::int64_t k = 0; k < a.z; ++k) {
      for (std::int64_t j = 0; j < a.y; ++j) {
        EXPECT_EQ(actual.row(j, k)[actual.row_words() - 1] >> (a.x % 64), 0u);
      }
    }
  }
}

void expect_same_grid(const Grid& a, const Grid& b) {
  EXPECT_EQ(a.dims, b.dims);
  EXPECT_EQ(a.origin, b.origin);
  EXPECT_EQ(a.voxel_size, b.voxel_size);
}

template <class Read>
ErrorCode error_code_of(const Read& read) {
  try {
    read();
  } catch (const Error& e) {
    EXPECT_GT(std::strlen(e.what()), 10u) << "error messages must say what is wrong";
    return e.code();
  }
  ADD_FAILURE() << "no voxd::Error thrown";
  return ErrorCode::io_error;
}

Bytes hex(const std::string& text) {
  Bytes out;
  for (std::size_t i = 0; i < text.size();) {
    if (text[i] == ' ') {
      ++i;
      continue;
    }
    out.push_back(static_cast<std::uint8_t>(std::stoi(text.substr(i, 2), nullptr, 16)));
    i += 2;
  }
  return out;
}

Bytes concat(std::initializer_list<Bytes> parts) {
  Bytes out;
  for (const Bytes& p : parts) out.insert(out.end(), p.begin(), p.end());
  return out;
}

Bytes ascii(const std::string& s) { return Bytes(s.begin(), s.end()); }

// RLE preamble + header for a JSON text, as the spec describes it.
Bytes rle_preamble(const std::string& json) {
  Bytes out = ascii("VOXDRLE");
  out.push_back(1);
  const auto n = static_cast<std::uint32_t>(json.size());
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<std::uint8_t>(n >> (8 * i)));
  return concat({out, ascii(json)});
}

// ------------------------------------------------------------------ names --

TEST(VolumeFormatNames, NamesExtensionsAndMediaTypes) {
  for (VolumeFormat f : {VolumeFormat::rle, VolumeFormat::binvox, VolumeFormat::raw, VolumeFormat::nrrd}) {
    EXPECT_EQ(volume_format_from_string(to_string(f)), f);
    EXPECT_EQ(volume_format_from_path(std::string("out/model") + file_extension(f)), f);
    EXPECT_NE(std::string(media_type(f)), "");
  }
  EXPECT_EQ(volume_format_from_string("vdb"), std::nullopt);
  EXPECT_EQ(volume_format_from_string(""), std::nullopt);
  EXPECT_EQ(volume_format_from_path("MODEL.BINVOX"), VolumeFormat::binvox);
  EXPECT_EQ(volume_format_from_path("a.Rle"), VolumeFormat::rle);
  EXPECT_EQ(volume_format_from_path("a.rle.gz"), std::nullopt);
  EXPECT_EQ(volume_format_from_path(".raw"), std::nullopt);  // no name before the extension
  EXPECT_EQ(volume_format_from_path("raw"), std::nullopt);
  EXPECT_STREQ(media_type(VolumeFormat::raw), "application/octet-stream");
  EXPECT_EQ(volume_format_from_path("sdf.NRRD"), VolumeFormat::nrrd);
  EXPECT_STREQ(media_type(VolumeFormat::nrrd), "application/x-nrrd");
}

// -------------------------------------------------------------------- RLE --

TEST(VolumeFormatRle, RoundTripsEveryTestVolume) {
  for (const auto& [name, volume] : test_volumes()) {
    SCOPED_TRACE(name);
    const Bytes stream = encode(volume, VolumeFormat::rle);
    const BitVolume back = read_rle_bits(stream);
    expect_same_grid(back.grid(), volume.grid());
    expect_same_voxels(volume, back);
  }
}

TEST(VolumeFormatRle, RoundTripsManyRandomShapes) {
  std::mt19937 rng(42);
  for (int n = 0; n < 60; ++n) {
    const glm::i64vec3 dims(1 + rng() % 150, 1 + rng() % 9, 1 + rng() % 6);
    const double density = std::uniform_real_distribution<double>(0.0, 1.0)(rng);
    const BitVolume volume = random_volume(make_grid(dims), rng(), density);
    const BitVolume back = read_rle_bits(encode(volume, VolumeFormat::rle));
    expect_same_voxels(volume, back);
  }
}

// The example of proto-schemas/rle-format.md, byte for byte.
TEST(VolumeFormatRle, BitStreamMatchesTheSpecExample) {
  BitVolume v(make_grid({3, 2, 2}, {-1.5, 0.0, 2.25}, 0.5));
  v.set(1, 0, 0, true);
  v.set(2, 0, 0, true);
  v.set(0, 1, 0, true);
  for (std::int64_t j = 0; j < 2; ++j)
    for (std::int64_t i = 0; i < 3; ++i) v.set(i, j, 1, true);

  const Bytes expected = concat({
      hex("56 4f 58 44 52 4c 45 01"),  // "VOXDRLE", version 1
      hex("60 00 00 00"),              // header length 96
      ascii(R"({"dims":[3,2,2],"origin":[-1.5,0.0,2.25],"voxel_size":0.5,"axis_order":"xyz","value_type":"bit"})"),
      hex("53 00 03 01 03 02"),  // slab 0: runs 1 zero, 3 ones, 2 zeros
      hex("53 01 02 00 06"),     // slab 1: runs 0 zeros, 6 ones
      hex("45 02"),              // end, 2 slabs
  });
  EXPECT_EQ(encode(v, VolumeFormat::rle), expected);
  expect_same_voxels(v, read_rle_bits(expected));
}

TEST(VolumeFormatRle, U8StreamMatchesTheSpecExample) {
  DenseVolume<std::uint8_t> v(make_grid({2, 2, 1}));
  v.values() = {7, 7, 7, 200};
  const Bytes expected = concat({
      hex("56 4f 58 44 52 4c 45 01 5d 00 00 00"),
      ascii(R"({"dims":[2,2,1],"origin":[0.0,0.0,0.0],"voxel_size":1.0,"axis_order":"xyz","value_type":"u8"})"),
      hex("53 00 04 03 07 01 c8"),  // slab 0: 3 x 7, 1 x 200
      hex("45 01"),
  });
  EXPECT_EQ(rle_u8(v), expected);
  EXPECT_EQ(read_rle_u8(expected).values(), v.values());
}

TEST(VolumeFormatRle, LongRunsUseMultiByteVarints) {
  // 200 x 1 x 1, voxels 0..149 empty, 150..199 set: runs 150 (0x96 0x01) and 50.
  BitVolume v(make_grid({200, 1, 1}));
  for (int i = 150; i < 200; ++i) v.set(i, 0, 0, true);
  const Bytes stream = encode(v, VolumeFormat::rle);
  const Bytes tail = hex("53 00 03 96 01 32 45 01");
  ASSERT_GT(stream.size(), tail.size());
  EXPECT_EQ(Bytes(stream.end() - static_cast<std::ptrdiff_t>(tail.size()), stream.end()), tail);
}

TEST(VolumeFormatRle, U8RoundTrips) {
  for (const glm::i64vec3 dims : {glm::i64vec3(67, 5, 3), glm::i64vec3(1, 1, 1), glm::i64vec3(100, 40, 12)}) {
    const DenseVolume<std::uint8_t> v = random_u8_volume(make_grid(dims, {1, 2, 3}, 0.7), 9);
    const DenseVolume<std::uint8_t> back = read_rle_u8(rle_u8(v));
    expect_same_grid(back.grid(), v.grid());
    EXPECT_EQ(back.values(), v.values());
  }
  DenseVolume<std::uint8_t> constant(make_grid({70, 9, 4}), 255);
  EXPECT_EQ(read_rle_u8(rle_u8(constant)).values(), constant.values());
}

DenseVolume<float> random_f32_volume(const Grid& grid, unsigned seed) {
  std::mt19937 rng(seed);
  DenseVolume<float> v(grid, 0.0f);
  // Runs of repeated values (as a clamped distance band has), specials too.
  const float specials[] = {0.0f, -0.0f, 3.0f, -3.0f, std::numeric_limits<float>::infinity(), 1e-38f};
  for (std::size_t i = 0; i < v.values().size();) {
    const float value = rng() % 3 == 0 ? specials[rng() % 6] : std::uniform_real_distribution<float>(-5, 5)(rng);
    for (std::size_t n = 1 + rng() % 20; n > 0 && i < v.values().size(); --n) v.values()[i++] = value;
  }
  return v;
}

Bytes rle_f32(const DenseVolume<float>& v) {
  VectorSink sink;
  write_rle(v, sink);
  return sink.data;
}

TEST(VolumeFormatRle, F32RoundTripsBitForBit) {
  for (const glm::i64vec3 dims : {glm::i64vec3(67, 5, 3), glm::i64vec3(1, 1, 1), glm::i64vec3(30, 20, 9)}) {
    const DenseVolume<float> v = random_f32_volume(make_grid(dims, {1, 2, 3}, 0.7), 13);
    const DenseVolume<float> back = read_rle_f32(rle_f32(v));
    expect_same_grid(back.grid(), v.grid());
    ASSERT_EQ(back.values().size(), v.values().size());
    EXPECT_EQ(std::memcmp(back.values().data(), v.values().data(), v.values().size() * 4), 0);  // -0.0 stays -0.0
  }
  // The wrong reader names what the stream holds.
  const Bytes stream = rle_f32(random_f32_volume(make_grid({4, 3, 2}), 14));
  EXPECT_EQ(error_code_of([&] { read_rle_u8(stream); }), ErrorCode::malformed_input);
  EXPECT_EQ(error_code_of([&] { read_rle_bits(stream); }), ErrorCode::malformed_input);
  for (std::size_t n = 0; n < stream.size(); ++n)
    EXPECT_EQ(error_code_of([&] { read_rle_f32(std::span(stream.data(), n)); }), ErrorCode::truncated_input) << n;
  // A valid stream over the reader's limit allocates nothing.
  EXPECT_EQ(error_code_of([&] { read_rle_f32(stream, ReadLimits{4 * 4 * 3 * 2 - 1}); }), ErrorCode::limit_exceeded);
  EXPECT_EQ(read_rle_f32(stream, ReadLimits{4 * 4 * 3 * 2}).values().size(), 24u);
}

TEST(VolumeFormatRle, QuantizedFloatsRecoverWithinHalfAStepAndZeroStaysZero) {
  // A clamped band around a surface, as a distance field has: values in
  // [-1.5, 1.5], runs of the clamp, a NaN and infinities.
  DenseVolume<float> v = random_f32_volume(make_grid({40, 9, 5}, {1, 2, 3}, 0.5), 51);
  for (float& x : v.values()) x = std::isfinite(x) ? std::clamp(x, -1.5f, 1.5f) : x;
  v.values()[7] = std::numeric_limits<float>::quiet_NaN();
  v.values()[8] = 0.0f;
  for (Quantize levels : {Quantize::u8, Quantize::u16}) {
    VectorSink sink;
    write_rle_quantized(v, levels, "signed distance (model units)", sink);
    const nlohmann::json meta = nlohmann::json::parse(read_rle_metadata(sink.data)).at("quantization");
    const double offset = meta.at("offset"), scale = meta.at("scale");
    const std::uint32_t top = levels == Quantize::u8 ? 254 : 65534;
    EXPECT_EQ(meta.at("levels"), top + 1);
    EXPECT_EQ(meta.at("nan_level"), top + 1);
    EXPECT_EQ(meta.at("content"), "signed distance (model units)");
    EXPECT_DOUBLE_EQ(offset, -1.5);  // symmetric: the values have both signs
    EXPECT_DOUBLE_EQ(scale, 3.0 / top);
    std::vector<std::uint32_t> q;
    if (levels == Quantize::u8) {
      const DenseVolume<std::uint8_t> decoded = read_rle_u8(sink.data);
      q.assign(decoded.values().begin(), decoded.values().end());
    } else {
      const DenseVolume<std::uint16_t> decoded = read_rle_u16(sink.data);
      q.assign(decoded.values().begin(), decoded.values().end());
    }
    ASSERT_EQ(q.size(), v.values().size());
    for (std::size_t i = 0; i < q.size(); ++i) {
      const float x = v.values()[i];
      if (std::isnan(x)) {
        EXPECT_EQ(q[i], top + 1);
      } else {
        ASSERT_LE(q[i], top);
        EXPECT_NEAR(offset + scale * q[i], std::clamp(static_cast<double>(x), -1.5, 1.5), scale / 2 * (1 + 1e-9)) << i;
      }
    }
    EXPECT_EQ(q[8], top / 2) << "zero is a level exactly";
  }
  // Non-negative values keep their own range: coverage fractions in [0, 1].
  DenseVolume<float> fractions(make_grid({3, 2, 1}), 0.0f);
  fractions.values() = {0.0f, 0.1f, 0.3f, 0.6f, 0.9f, 1.0f};
  VectorSink sink;
  write_rle_quantized(fractions, Quantize::u8, "coverage", sink);
  const nlohmann::json meta = nlohmann::json::parse(read_rle_metadata(sink.data)).at("quantization");
  EXPECT_EQ(meta.at("offset"), 0.0);
  EXPECT_DOUBLE_EQ(meta.at("scale").get<double>(), 1.0 / 254);
  EXPECT_EQ(read_rle_u8(sink.data).values(), (VolumeVector<std::uint8_t>{0, 25, 76, 152, 229, 254}));
  // Quantizing is for floats in rle: anything else is refused with the reason.
  EncodeOptions quantized;
  quantized.quantize = Quantize::u16;
  EXPECT_TRUE(format_refusal(ValueVolume(fractions), VolumeFormat::nrrd, quantized));
  EXPECT_TRUE(format_refusal(ValueVolume(random_u8_volume(make_grid({2, 2, 2}), 1)), VolumeFormat::rle, quantized));
  EXPECT_FALSE(format_refusal(ValueVolume(fractions), VolumeFormat::rle, quantized));
  VectorSink via;
  encode_volume(ValueVolume(fractions), VolumeFormat::rle, via, EncodeOptions{RawPacking::bytes, NrrdEncoding::raw, "coverage", Quantize::u8});
  EXPECT_EQ(via.data, sink.data);
  EXPECT_EQ(read_rle_metadata(rle_f32(fractions)), "");
}

TEST(VolumeFormatRle, ReaderAcceptsNonCanonicalRuns) {
  // The spec lets runs be split by zero-length runs (bits) or repeat a value
  // (u8); voxd never writes that, other writers may.
  const std::string bit_header =
      R"({"dims":[3,1,1],"origin":[0,0,0],"voxel_size":1,"axis_order":"xyz","value_type":"bit","metadata":{"by":"test"},"future_key":[1]})";
  const BitVolume v = read_rle_bits(concat({rle_preamble(bit_header), hex("53 00 05 01 01 00 01 00 45 01")}));
  EXPECT_FALSE(v.get(0, 0, 0));
  EXPECT_TRUE(v.get(1, 0, 0));
  EXPECT_TRUE(v.get(2, 0, 0));
  const std::string u8_header = R"({"dims":[3,1,1],"origin":[0,0,0],"voxel_size":1,"axis_order":"xyz","value_type":"u8"})";
  const auto u8 = read_rle_u8(concat({rle_preamble(u8_header), hex("53 00 08 01 05 00 09 01 05 01 06 45 01")}));
  EXPECT_EQ(u8.values(), (VolumeVector<std::uint8_t>{5, 5, 6}));
  // A zero-length run after the slab is covered is still a run of the payload.
  const std::string header = R"({"dims":[3,2,1],"origin":[0,0,0],"voxel_size":1,"axis_order":"xyz","value_type":"bit"})";
  EXPECT_EQ(read_rle_bits(concat({rle_preamble(header), hex("53 00 04 01 03 02 00 45 01")})).count(), 3u);
}

TEST(VolumeFormatRle, EveryTruncationIsReportedAsTruncated) {
  const Bytes stream = encode(random_volume(make_grid({67, 5, 3}), 11), VolumeFormat::rle);
  for (std::size_t n = 0; n < stream.size(); ++n) {
    const std::span<const std::uint8_t> prefix(stream.data(), n);
    EXPECT_EQ(error_code_of([&] { read_rle_bits(prefix); }), ErrorCode::truncated_input) << "prefix " << n;
  }
  const Bytes u8_stream = rle_u8(random_u8_volume(make_grid({9, 4, 3}), 12));
  for (std::size_t n = 0; n < u8_stream.size(); ++n)
    EXPECT_EQ(error_code_of([&] { read_rle_u8(std::span(u8_stream.data(), n)); }), ErrorCode::truncated_input)
        << "prefix " << n;
}

TEST(VolumeFormatRle, CorruptStreamsAreMalformed) {
  const std::string header = R"({"dims":[3,2,2],"origin":[0,0,0],"voxel_size":1,"axis_order":"xyz","value_type":"bit"})";
  const Bytes good_blocks = hex("53 00 03 01 03 02 53 01 02 00 06 45 02");
  ASSERT_NO_THROW(read_rle_bits(concat({rle_preamble(header), good_blocks})));

  const auto bad_blocks = [&](const std::string& blocks) {
    return error_code_of([&] { read_rle_bits(concat({rle_preamble(header), hex(blocks)})); });
  };
  EXPECT_EQ(bad_blocks("53 00 03 01 03 03 53 01 02 00 06 45 02"), ErrorCode::malformed_input);  // 7 voxels
  EXPECT_EQ(bad_blocks("53 00 02 01 03 53 01 02 00 06 45 02"), ErrorCode::malformed_input);     // 4 voxels
  EXPECT_EQ(bad_blocks("53 00 04 01 03 02 05 53 01 02 00 06 45 02"), ErrorCode::malformed_input);  // run past slab
  EXPECT_EQ(bad_blocks("53 00 02 01 83 53 01 02 00 06 45 02"), ErrorCode::malformed_input);  // varint cut by payload end
  EXPECT_EQ(bad_blocks("53 01 03 01 03 02 53 00 02 00 06 45 02"), ErrorCode::malformed_input);  // slabs out of order
  EXPECT_EQ(bad_blocks("53 00 03 01 03 02 45 01"), ErrorCode::malformed_input);                 // end too early
  EXPECT_EQ(bad_blocks("53 00 03 01 03 02 53 01 02 00 06 53 02 01 06 45 03"), ErrorCode::malformed_input);
  EXPECT_EQ(bad_blocks("53 00 03 01 03 02 53 01 02 00 06 45 03"), ErrorCode::malformed_input);  // wrong count
  EXPECT_EQ(bad_blocks("53 00 03 01 03 02 53 01 02 00 06 46 02"), ErrorCode::malformed_input);  // bad end tag
  EXPECT_EQ(bad_blocks("54 00 03 01 03 02 53 01 02 00 06 45 02"), ErrorCode::malformed_input);  // bad slab tag
  EXPECT_EQ(bad_blocks("53 00 03 01 03 02 53 01 02 00 06 45 02 00"), ErrorCode::malformed_input);  // trailing byte
  EXPECT_EQ(bad_blocks("53 00 ff ff ff ff ff ff ff ff ff ff 01"), ErrorCode::malformed_input);  // 11-byte varint
  EXPECT_EQ(bad_blocks("53 00 ff ff ff ff ff ff ff ff ff 02"), ErrorCode::malformed_input);     // varint >= 2^64
  EXPECT_EQ(bad_blocks("53 00 ff ff ff ff ff ff ff ff ff 01"), ErrorCode::truncated_input);  // 2^64-1 byte payload

  const auto bad_header = [&](const Bytes& preamble) {
    return error_code_of([&] { read_rle_bits(concat({preamble, good_blocks})); });
  };
  EXPECT_EQ(bad_header(concat({ascii("VOXDRLF"), hex("01 02 00 00 00"), ascii("{}")})), ErrorCode::malformed_input);
  EXPECT_EQ(bad_header(concat({ascii("VOXDRLE"), hex("02 02 00 00 00"), ascii("{}")})), ErrorCode::malformed_input);
  EXPECT_EQ(bad_header(concat({ascii("VOXDRLE"), hex("01 ff ff ff 7f")})), ErrorCode::malformed_input);  // 2 GiB header
  const std::vector<std::string> bad_json = {
      "",
      "{",
      "[]",
      "null",
      R"({"dims":[3,2],"origin":[0,0,0],"voxel_size":1,"axis_order":"xyz","value_type":"bit"})",
      R"({"dims":[3,2,2.0],"origin":[0,0,0],"voxel_size":1,"axis_order":"xyz","value_type":"bit"})",
      R"({"dims":[3,-2,2],"origin":[0,0,0],"voxel_size":1,"axis_order":"xyz","value_type":"bit"})",
      R"({"dims":[3,0,2],"origin":[0,0,0],"voxel_size":1,"axis_order":"xyz","value_type":"bit"})",
      R"({"dims":[3,2,65537],"origin":[0,0,0],"voxel_size":1,"axis_order":"xyz","value_type":"bit"})",
      R"({"dims":[3,2,18446744073709551616],"origin":[0,0,0],"voxel_size":1,"axis_order":"xyz","value_type":"bit"})",
      R"({"dims":"3,2,2","origin":[0,0,0],"voxel_size":1,"axis_order":"xyz","value_type":"bit"})",
      R"({"dims":[3,2,2],"origin":[0,"0",0],"voxel_size":1,"axis_order":"xyz","value_type":"bit"})",
      R"({"dims":[3,2,2],"origin":[0,1e999,0],"voxel_size":1,"axis_order":"xyz","value_type":"bit"})",
      R"({"dims":[3,2,2],"origin":[0,0,0],"voxel_size":0,"axis_order":"xyz","value_type":"bit"})",
      R"({"dims":[3,2,2],"origin":[0,0,0],"voxel_size":-1,"axis_order":"xyz","value_type":"bit"})",
      R"({"dims":[3,2,2],"origin":[0,0,0],"axis_order":"xyz","value_type":"bit"})",
      R"({"dims":[3,2,2],"origin":[0,0,0],"voxel_size":1,"axis_order":"zyx","value_type":"bit"})",
      R"({"dims":[3,2,2],"origin":[0,0,0],"voxel_size":1,"value_type":"bit"})",
      R"({"dims":[3,2,2],"origin":[0,0,0],"voxel_size":1,"axis_order":"xyz","value_type":"bool"})",
      R"({"dims":[3,2,2],"origin":[0,0,0],"voxel_size":1,"axis_order":"xyz","value_type":"u8"})",  // wrong reader
      R"({"dims":[3,2,2],"origin":[0,0,0],"voxel_size":1,"axis_order":"xyz","value_type":"bit","metadata":3})",
      "{\"dims\":[3,2,2],\"origin\":[0,0,0],\"voxel_size\":1,\"axis_order\":\"xyz\",\"value_type\":\"bit\",\"x\":\"\xff\"}",
      std::string(100000, '[') + std::string(100000, ']'),  // deep nesting must not overflow the stack
  };
  for (const std::string& json : bad_json)
    EXPECT_EQ(bad_header(rle_preamble(json)), ErrorCode::malformed_input) << json.substr(0, 120);
}

TEST(VolumeFormatRle, LyingHeaderAllocatesNothing) {
  // 65536^3 voxels (32 TiB as bits) announced by a few dozen bytes: the
  // validation pass fails before any allocation (ASan would abort otherwise).
  const std::string huge = R"({"dims":[65536,65536,65536],"origin":[0,0,0],"voxel_size":1,"axis_order":"xyz","value_type":"bit"})";
  EXPECT_EQ(error_code_of([&] { read_rle_bits(concat({rle_preamble(huge), hex("53 00 05 80 80 80 80 10")})); }),
            ErrorCode::truncated_input);
  EXPECT_EQ(error_code_of([&] { read_rle_bits(concat({rle_preamble(huge), hex("53 00 06 00 80 80 80 80 10 45 01")})); }),
            ErrorCode::malformed_input);
  // A valid stream of a 65536 x 65536 x 1 full slab (512 MiB) in 21 bytes:
  // legitimate, so only the configurable limit stops it.
  const std::string big = R"({"dims":[65536,65536,1],"origin":[0,0,0],"voxel_size":1,"axis_order":"xyz","value_type":"bit"})";
  ReadLimits limits;
  limits.max_volume_bytes = 1 << 20;
  EXPECT_EQ(error_code_of([&] { read_rle_bits(concat({rle_preamble(big), hex("53 00 06 00 80 80 80 80 10 45 01")}), limits); }),
            ErrorCode::limit_exceeded);
}

// Volumes over the single-thread threshold go through the parallel pipeline,
// and with more slabs than its slots, through slot reuse: the stream must be
// identical to the one a single thread would write (the spec has one
// encoding per volume) and read back the same.
TEST(VolumeFormatRle, ParallelEncodingKeepsSlabOrder) {
  // 4 KiB slabs: 400 KiB in all is over the 256 KiB single-thread threshold,
  // and 100 slabs are more than the 64 slots.
  const BitVolume volume = random_volume(make_grid({512, 64, 100}), 31, 0.001);
  const Bytes stream = encode(volume, VolumeFormat::rle);
  expect_same_voxels(volume, read_rle_bits(stream));
  // Cut the volume into single slabs: each encodes alone, single-threaded,
  // and its slab block must appear in the big stream unchanged.
  for (std::int64_t k : {0, 1, 63, 64, 65, 99}) {
    BitVolume one(make_grid({512, 64, 1}));
    std::copy(volume.slab(k), volume.slab(k) + volume.slab_words(), one.slab(0));
    const Bytes single = encode(one, VolumeFormat::rle);
    // Payload of slab 0 in `single`: after the header, tag, index 0, length.
    const std::size_t header_end = 12 + (single[8] | single[9] << 8);
    const Bytes payload(single.begin() + static_cast<std::ptrdiff_t>(header_end), single.end() - 2);
    Bytes needle = payload;
    needle[1] = static_cast<std::uint8_t>(k);  // slab index < 128: one varint byte
    EXPECT_NE(std::search(stream.begin(), stream.end(), needle.begin(), needle.end()), stream.end()) << "slab " << k;
  }
  const DenseVolume<std::uint8_t> u8 = random_u8_volume(make_grid({300, 100, 90}), 32);
  EXPECT_EQ(read_rle_u8(rle_u8(u8)).values(), u8.values());
}

// Over 1 MiB, binvox gathers word columns on worker threads while the
// calling thread emits runs (5 columns here, more than the slots).
TEST(VolumeFormatBinvox, ParallelWriterKeepsColumnOrder) {
  const BitVolume volume = random_words_volume(make_grid({300, 140, 200}, {1, 2, 3}, 0.5), 34);
  ASSERT_GE(volume.byte_size(), std::size_t{1} << 20);
  expect_same_voxels(volume, read_binvox(encode(volume, VolumeFormat::binvox)));
}

// A sink that fails after some writes, like a client that disconnects.
class FailingSink final : public ByteSink {
 public:
  explicit FailingSink(int writes_before_failure) : left_(writes_before_failure) {}
  using ByteSink::write;
  void write(std::span<const std::uint8_t>) override {
    if (left_-- == 0) throw Error(ErrorCode::io_error, "connection lost");
  }

 private:
  int left_;
};

TEST(VolumeFormatRle, SinkFailureStopsEveryEncoderWithoutHanging) {
  // Over 1 MiB: every encoder takes its parallel path.
  const BitVolume volume = random_words_volume(make_grid({300, 140, 200}), 33);
  for (VolumeFormat f : {VolumeFormat::rle, VolumeFormat::binvox, VolumeFormat::raw}) {
    class CountingSink final : public ByteSink {
     public:
      using ByteSink::write;
      void write(std::span<const std::uint8_t>) override { ++writes; }
      int writes = 0;
    } counter;
    encode_volume(volume, f, counter);
    ASSERT_GE(counter.writes, 3) << to_string(f);
    for (int n : {0, 1, counter.writes / 2, counter.writes - 1}) {
      FailingSink sink(n);
      EXPECT_EQ(error_code_of([&] { encode_volume(volume, f, sink); }), ErrorCode::io_error)
          << to_string(f) << " after " << n << " writes";
    }
  }
}

TEST(VolumeFormatRle, WritersRejectVolumesWithoutVoxels) {
  VectorSink sink;
  EXPECT_EQ(error_code_of([&] { write_rle(BitVolume(), sink); }), ErrorCode::invalid_argument);
  EXPECT_EQ(error_code_of([&] { write_binvox(BitVolume(), sink); }), ErrorCode::invalid_argument);
  EXPECT_EQ(error_code_of([&] { write_raw(BitVolume(), RawPacking::bits, sink); }), ErrorCode::invalid_argument);
  EXPECT_EQ(error_code_of([&] { write_rle(DenseVolume<std::uint8_t>(), sink); }), ErrorCode::invalid_argument);
  DenseVolume<std::uint8_t> resized(make_grid({2, 2, 2}));
  resized.values().pop_back();
  EXPECT_EQ(error_code_of([&] { write_binvox(resized, sink); }), ErrorCode::invalid_argument);
  EXPECT_TRUE(sink.data.empty());
}

// ----------------------------------------------------------------- binvox --

TEST(VolumeFormatBinvox, RoundTripsEveryTestVolumeWithPadding) {
  for (const auto& [name, volume] : test_volumes()) {
    SCOPED_TRACE(name);
    const Grid& g = volume.grid();
    const BitVolume back = read_binvox(encode(volume, VolumeFormat::binvox));
    const std::int64_t d = std::max({g.dims.x, g.dims.y, g.dims.z});
    EXPECT_EQ(back.grid().dims, glm::i64vec3(d));
    EXPECT_EQ(back.grid().origin, g.origin);
    EXPECT_DOUBLE_EQ(back.grid().voxel_size, g.voxel_size);
    expect_same_voxels(volume, back);
  }
}

TEST(VolumeFormatBinvox, HeaderFieldsAreExact) {
  // 4 x 2 x 3 pads to a 4^3 cube; scale = 4 * 0.25.
  BitVolume v(make_grid({4, 2, 3}, {1.0, -2.0, 0.5}, 0.25));
  const Bytes bytes = encode(v, VolumeFormat::binvox);
  const std::string header = "#binvox 1\ndim 4 4 4\ntranslate 1 -2 0.5\nscale 1\ndata\n";
  ASSERT_GE(bytes.size(), header.size());
  EXPECT_EQ(std::string(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(header.size())), header);
  // An empty 4^3 volume is one run of 64 zeros.
  EXPECT_EQ(Bytes(bytes.begin() + static_cast<std::ptrdiff_t>(header.size()), bytes.end()), hex("00 40"));

  BitVolume w(make_grid({2, 1, 1}, {0.1, 0.2, 0.3}, 0.1));
  w.set(1, 0, 0, true);  // binvox index x*4 + z*2 + y = 4 in the padded 2^3 cube
  const Bytes wb = encode(w, VolumeFormat::binvox);
  const std::string wheader = "#binvox 1\ndim 2 2 2\ntranslate 0.1 0.2 0.3\nscale 0.2\ndata\n";
  EXPECT_EQ(wb, concat({ascii(wheader), hex("00 04 01 01 00 03")}));
}

TEST(VolumeFormatBinvox, LongRunsAreSplitAt255) {
  const BitVolume full = full_volume(make_grid({10, 10, 10}));  // 1000 = 3 * 255 + 235
  const Bytes bytes = encode(full, VolumeFormat::binvox);
  const Bytes data(bytes.end() - 8, bytes.end());
  EXPECT_EQ(data, hex("01 ff 01 ff 01 ff 01 eb"));
}

TEST(VolumeFormatBinvox, RandomShapesRoundTrip) {
  std::mt19937 rng(7);
  for (int n = 0; n < 40; ++n) {
    const glm::i64vec3 dims(1 + rng() % 140, 1 + rng() % 70, 1 + rng() % 30);
    const BitVolume volume = random_volume(make_grid(dims), rng(), rng() % 2 ? 0.5 : 0.05);
    expect_same_voxels(volume, read_binvox(encode(volume, VolumeFormat::binvox)));
  }
}

TEST(VolumeFormatBinvox, U8VolumesUseVersion2) {
  for (const glm::i64vec3 dims : {glm::i64vec3(9, 4, 3), glm::i64vec3(40, 41, 17), glm::i64vec3(1, 1, 1)}) {
    const DenseVolume<std::uint8_t> v = random_u8_volume(make_grid(dims, {1, 2, 3}, 0.5), 5);
    const Bytes bytes = binvox_u8(v);
    ASSERT_EQ(std::string(bytes.begin(), bytes.begin() + 10), "#binvox 2\n");
    const DenseVolume<std::uint8_t> back = read_binvox_u8(bytes);
    const std::int64_t d = std::max({dims.x, dims.y, dims.z});
    ASSERT_EQ(back.grid().dims, glm::i64vec3(d));
    for (std::int64_t k = 0; k < d; ++k)
      for (std::int64_t j = 0; j < d; ++j)
        for (std::int64_t i = 0; i < d; ++i) {
          const bool inside = i < dims.x && j < dims.y && k < dims.z;
          ASSERT_EQ(back.at(i, j, k), inside ? v.at(i, j, k) : 0) << i << "," << j << "," << k;
        }
    // The bit reader sets exactly the non-zero voxels of a version 2 file.
    const BitVolume bits = read_binvox(bytes);
    for (std::int64_t k = 0; k < dims.z; ++k)
      for (std::int64_t j = 0; j < dims.y; ++j)
        for (std::int64_t i = 0; i < dims.x; ++i) ASSERT_EQ(bits.get(i, j, k), v.at(i, j, k) != 0);
  }
}

TEST(VolumeFormatBinvox, ReaderFollowsTheReferenceReader) {
  // Unknown lines skipped, header lines in any order, translate/scale optional,
  // bytes after the last voxel ignored.
  const Bytes file = concat({ascii("#binvox 1\nscale 2\ncomment made by hand\n\ndim 2 2 2\ndata\n"),
                             hex("00 07 01 01 ff ff")});
  const BitVolume v = read_binvox(file);
  EXPECT_EQ(v.grid().dims, glm::i64vec3(2));
  EXPECT_EQ(v.grid().origin, glm::dvec3(0.0));
  EXPECT_EQ(v.grid().voxel_size, 1.0);
  EXPECT_EQ(v.count(), 1u);
  EXPECT_TRUE(v.get(1, 1, 1));  // index 7 = x 1, z 1, y 1
}

TEST(VolumeFormatBinvox, TruncationsAndCorruptionsAreErrors) {
  const Bytes file = encode(random_volume(make_grid({9, 7, 5}), 13), VolumeFormat::binvox);
  for (std::size_t n = 0; n < file.size(); ++n)
    EXPECT_EQ(error_code_of([&] { read_binvox(std::span(file.data(), n)); }), ErrorCode::truncated_input)
        << "prefix " << n;

  const auto code = [](const std::string& header, const std::string& data = "00 08") {
    return error_code_of([&] { read_binvox(concat({ascii(header), hex(data)})); });
  };
  EXPECT_EQ(code("#binvax 1\ndim 2 2 2\ndata\n"), ErrorCode::malformed_input);
  EXPECT_EQ(code("#binvox 3\ndim 2 2 2\ndata\n"), ErrorCode::malformed_input);
  EXPECT_EQ(code("#binvox\ndim 2 2 2\ndata\n"), ErrorCode::malformed_input);
  EXPECT_EQ(code("#binvox 1\ndata\n"), ErrorCode::malformed_input);  // no dim
  EXPECT_EQ(code("#binvox 1\ndim 2 2 3\ndata\n"), ErrorCode::malformed_input);
  EXPECT_EQ(code("#binvox 1\ndim 2 2\ndata\n"), ErrorCode::malformed_input);
  EXPECT_EQ(code("#binvox 1\ndim 0 0 0\ndata\n"), ErrorCode::malformed_input);
  EXPECT_EQ(code("#binvox 1\ndim -2 -2 -2\ndata\n"), ErrorCode::malformed_input);
  EXPECT_EQ(code("#binvox 1\ndim 99999 99999 99999\ndata\n"), ErrorCode::malformed_input);
  EXPECT_EQ(code("#binvox 1\ndim 2x 2 2\ndata\n"), ErrorCode::malformed_input);
  EXPECT_EQ(code("#binvox 1\ndim 2 2 2\nscale 0\ndata\n"), ErrorCode::malformed_input);
  EXPECT_EQ(code("#binvox 1\ndim 2 2 2\nscale nan\ndata\n"), ErrorCode::malformed_input);
  EXPECT_EQ(code("#binvox 1\ndim 2 2 2\ntranslate 1 2\ndata\n"), ErrorCode::malformed_input);
  EXPECT_EQ(code("#binvox 1\ndim 2 2 2\ndata now\n"), ErrorCode::malformed_input);
  EXPECT_EQ(code("#binvox 1\ndim 2 2 2\ndata\n", "00 07 01 02"), ErrorCode::malformed_input);  // past the end
  EXPECT_EQ(code("#binvox 1\ndim 2 2 2\ndata\n", "00 07"), ErrorCode::truncated_input);
  EXPECT_EQ(code("#binvox 1\ndim 4096 4096 4096\ndata\n", "01 ff 01 ff"), ErrorCode::truncated_input);  // lying dim
  EXPECT_EQ(code("#binvox 1\n" + std::string(70000, 'x')), ErrorCode::malformed_input);  // endless header

  ReadLimits limits;
  limits.max_volume_bytes = 100;
  EXPECT_EQ(error_code_of([&] { read_binvox(file, limits); }), ErrorCode::limit_exceeded);
}

// -------------------------------------------------------------------- raw --

TEST(VolumeFormatRaw, RoundTripsBothPackings) {
  for (const auto& [name, volume] : test_volumes()) {
    SCOPED_TRACE(name);
    const Grid& g = volume.grid();
    const Bytes bytes = encode(volume, VolumeFormat::raw, RawPacking::bytes);
    const Bytes bits = encode(volume, VolumeFormat::raw, RawPacking::bits);
    ASSERT_EQ(bytes.size(), g.voxel_count());
    ASSERT_EQ(bits.size(), (g.voxel_count() + 7) / 8);
    // Check the layout itself, voxel by voxel, against the documented order.
    std::size_t n = 0;
    for (std::int64_t k = 0; k < g.dims.z; ++k)
      for (std::int64_t j = 0; j < g.dims.y; ++j)
        for (std::int64_t i = 0; i < g.dims.x; ++i, ++n) {
          ASSERT_EQ(bytes[n], volume.get(i, j, k) ? 1 : 0);
          ASSERT_EQ((bits[n / 8] >> (n % 8)) & 1, volume.get(i, j, k) ? 1 : 0);
        }
    expect_same_voxels(volume, read_raw(bytes, g, RawPacking::bytes));
    expect_same_voxels(volume, read_raw(bits, g, RawPacking::bits));
  }
}

TEST(VolumeFormatRaw, ReaderChecksSizeValuesAndGrid) {
  const Grid g = make_grid({3, 2, 2});  // 12 voxels: 12 bytes or 2 bytes of bits
  EXPECT_EQ(error_code_of([&] { read_raw(Bytes(11, 0), g, RawPacking::bytes); }), ErrorCode::truncated_input);
  EXPECT_EQ(error_code_of([&] { read_raw(Bytes(13, 0), g, RawPacking::bytes); }), ErrorCode::malformed_input);
  Bytes two = Bytes(12, 1);
  two[7] = 2;
  EXPECT_EQ(error_code_of([&] { read_raw(two, g, RawPacking::bytes); }), ErrorCode::malformed_input);
  EXPECT_EQ(error_code_of([&] { read_raw(Bytes(1, 0), g, RawPacking::bits); }), ErrorCode::truncated_input);
  EXPECT_EQ(error_code_of([&] { read_raw(hex("ff 10"), g, RawPacking::bits); }), ErrorCode::malformed_input);
  EXPECT_EQ(read_raw(hex("ff 0f"), g, RawPacking::bits).count(), 12u);
  EXPECT_EQ(error_code_of([&] { read_raw(Bytes(1, 0), make_grid({0, 1, 1}), RawPacking::bytes); }),
            ErrorCode::invalid_argument);
  EXPECT_EQ(error_code_of([&] { read_raw(Bytes(1, 0), make_grid({1, 1, 70000}), RawPacking::bytes); }),
            ErrorCode::invalid_argument);
}

// ------------------------------------------- independent Python readers --

struct ToolRun {
  int status = -1;
  std::string stdout_text;
  Bytes voxels;
};

std::string temp_path(const std::string& name) {
  return (std::filesystem::path(::testing::TempDir()) /
          ("voxd_volume_format_" + std::to_string(::getpid()) + "_" + name))
      .string();
}

ToolRun run_tool(const std::string& tool, const Bytes& input) {
  const std::string in = temp_path("in");
  const std::string out = temp_path("out");
  {
    std::ofstream f(in, std::ios::binary);
    f.write(reinterpret_cast<const char*>(input.data()), static_cast<std::streamsize>(input.size()));
  }
  const std::string command =
      std::string("/usr/bin/python3 ") + VOXD_SOURCE_DIR + "/tests/tools/" + tool + " " + in + " " + out;
  ToolRun run;
  if (FILE* pipe = ::popen(command.c_str(), "r")) {
    char buffer[4096];
    while (const std::size_t n = std::fread(buffer, 1, sizeof buffer, pipe)) run.stdout_text.append(buffer, n);
    run.status = ::pclose(pipe);
  }
  std::ifstream f(out, std::ios::binary);
  run.voxels.assign(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
  std::filesystem::remove(in);
  std::filesystem::remove(out);
  return run;
}

// Voxels in x-fastest order, one byte each, over `dims` (>= the volume's).
Bytes voxel_bytes(const BitVolume& v, glm::i64vec3 dims) {
  Bytes out;
  for (std::int64_t k = 0; k < dims.z; ++k)
    for (std::int64_t j = 0; j < dims.y; ++j)
      for (std::int64_t i = 0; i < dims.x; ++i) {
        const glm::i64vec3 d = v.grid().dims;
        out.push_back(i < d.x && j < d.y && k < d.z && v.get(i, j, k) ? 1 : 0);
      }
  return out;
}

TEST(VolumeFormatIndependent, PythonRleReaderDecodesTheSameVoxels) {
  for (const auto& [name, volume] : test_volumes()) {
    SCOPED_TRACE(name);
    const ToolRun run = run_tool("read_rle.py", encode(volume, VolumeFormat::rle));
    ASSERT_EQ(run.status, 0) << run.stdout_text;
    const auto summary = nlohmann::json::parse(run.stdout_text);
    const Grid& g = volume.grid();
    EXPECT_EQ(summary["dims"], nlohmann::json({g.dims.x, g.dims.y, g.dims.z}));
    EXPECT_EQ(summary["origin"], nlohmann::json({g.origin.x, g.origin.y, g.origin.z}));
    EXPECT_EQ(summary["voxel_size"].get<double>(), g.voxel_size);
    EXPECT_EQ(summary["value_type"], "bit");
    EXPECT_EQ(summary["nonzero_voxels"].get<std::uint64_t>(), volume.count());
    EXPECT_TRUE(run.voxels == voxel_bytes(volume, g.dims)) << "decoded voxels differ";
  }
  const DenseVolume<std::uint8_t> u8 = random_u8_volume(make_grid({67, 5, 3}, {0.5, 0, 0}, 3.0), 17);
  const ToolRun run = run_tool("read_rle.py", rle_u8(u8));
  ASSERT_EQ(run.status, 0) << run.stdout_text;
  EXPECT_EQ(nlohmann::json::parse(run.stdout_text)["value_type"], "u8");
  EXPECT_TRUE(std::equal(run.voxels.begin(), run.voxels.end(), u8.values().begin(), u8.values().end()))
      << "decoded u8 voxels differ";
}

// The payload examples of section 8.3 of the spec, for the value types the
// C++ side does not read yet: the spec-only reader must decode them as stated.
TEST(VolumeFormatIndependent, PythonRleReaderDecodesTheSpecExamplesOfEveryValueType) {
  const auto stream = [](int nx, const std::string& type, const std::string& payload) {
    const std::string header = "{\"dims\":[" + std::to_string(nx) +
                               ",1,1],\"origin\":[0,0,0],\"voxel_size\":1,\"axis_order\":\"xyz\",\"value_type\":\"" +
                               type + "\"}";
    const Bytes p = hex(payload);
    return concat({rle_preamble(header), Bytes{0x53, 0x00, static_cast<std::uint8_t>(p.size())}, p, hex("45 01")});
  };
  struct Case {
    std::string type;
    int nx;
    std::string payload;
    std::string voxels;  // expected decoded values, little-endian
  };
  const std::vector<Case> cases = {
      {"u16", 4, "03 e8 03 01 05 00", "e8 03 e8 03 e8 03 05 00"},
      {"f32", 3, "02 00 00 00 3f 01 00 00 80 bf", "00 00 00 3f 00 00 00 3f 00 00 80 bf"},
      {"rgba8", 2, "02 ff 00 00 ff", "ff 00 00 ff ff 00 00 ff"},
      {"u8", 3, "02 09 01 00", "09 09 00"},
      {"bit", 200, "96 01 32", ""},
  };
  for (const Case& c : cases) {
    const ToolRun run = run_tool("read_rle.py", stream(c.nx, c.type, c.payload));
    ASSERT_EQ(run.status, 0) << c.type;
    EXPECT_EQ(nlohmann::json::parse(run.stdout_text)["value_type"], c.type);
    if (c.type == "bit") {
      Bytes expected(150, 0);
      expected.resize(200, 1);
      EXPECT_EQ(run.voxels, expected);
    } else {
      EXPECT_EQ(run.voxels, hex(c.voxels)) << c.type;
    }
  }
}

TEST(VolumeFormatIndependent, PythonRleReaderRejectsACorruptStream) {
  Bytes stream = encode(random_volume(make_grid({10, 3, 2}), 3), VolumeFormat::rle);
  stream.back() ^= 1;  // the end block's slab count
  EXPECT_NE(run_tool("read_rle.py", stream).status, 0);
}

// Colours in runs (a slice voxelization's bands), empty voxels between them,
// and colours that differ in one byte only, so a run must compare all four.
DenseVolume<Rgba8> random_rgba8_volume(const Grid& grid, unsigned seed) {
  std::mt19937 rng(seed);
  DenseVolume<Rgba8> v(grid);
  const Rgba8 palette[] = {{0, 0, 0, 0}, {255, 0, 0, 255}, {255, 0, 0, 254}, {255, 1, 0, 255}, {0, 0, 1, 255}, {7, 8, 9, 10}};
  for (std::size_t i = 0; i < v.values().size();) {
    const Rgba8 c = palette[rng() % 6];
    for (std::size_t n = 1 + rng() % 20; n > 0 && i < v.values().size(); --n) v.values()[i++] = c;
  }
  return v;
}

Bytes rle_rgba8(const DenseVolume<Rgba8>& v) {
  VectorSink sink;
  write_rle(v, sink);
  return std::move(sink.data);
}

TEST(VolumeFormatIndependent, Rgba8RleRoundTripsAndThePythonReaderAgrees) {
  for (const glm::i64vec3 dims : {glm::i64vec3(67, 5, 3), glm::i64vec3(1, 1, 1), glm::i64vec3(300, 200, 9)}) {
    const DenseVolume<Rgba8> v = random_rgba8_volume(make_grid(dims, {1, 2, 3}, 0.7), 21);
    const DenseVolume<Rgba8> back = read_rle_rgba8(rle_rgba8(v));
    expect_same_grid(back.grid(), v.grid());
    EXPECT_TRUE(back.values() == v.values());
  }
  // Spec 8.3's example: one slab of 2 voxels, both opaque red.
  DenseVolume<Rgba8> red(make_grid({2, 1, 1}), Rgba8{255, 0, 0, 255});
  const Bytes stream = rle_rgba8(red);
  const Bytes tail = hex("53 00 05 02 ff 00 00 ff 45 01");
  ASSERT_GT(stream.size(), tail.size());
  EXPECT_EQ(Bytes(stream.end() - static_cast<std::ptrdiff_t>(tail.size()), stream.end()), tail);
  EXPECT_EQ(error_code_of([&] { read_rle_u8(stream); }), ErrorCode::malformed_input);
  EXPECT_EQ(error_code_of([&] { read_rle_rgba8(rle_u8(DenseVolume<std::uint8_t>(make_grid({2, 1, 1})))); }),
            ErrorCode::malformed_input);
  for (std::size_t n = 0; n < stream.size(); ++n)
    EXPECT_EQ(error_code_of([&] { read_rle_rgba8(std::span(stream.data(), n)); }), ErrorCode::truncated_input) << n;
  EXPECT_EQ(error_code_of([&] { read_rle_rgba8(stream, ReadLimits{7}); }), ErrorCode::limit_exceeded);
  // The independent reader, written from the spec alone, decodes the same colours.
  const DenseVolume<Rgba8> v = random_rgba8_volume(make_grid({67, 5, 3}, {0.5, 0, 0}, 3.0), 22);
  const ToolRun run = run_tool("read_rle.py", rle_rgba8(v));
  ASSERT_EQ(run.status, 0) << run.stdout_text;
  EXPECT_EQ(nlohmann::json::parse(run.stdout_text)["value_type"], "rgba8");
  ASSERT_EQ(run.voxels.size(), 4 * v.values().size());
  EXPECT_EQ(std::memcmp(run.voxels.data(), v.values().data(), run.voxels.size()), 0) << "decoded colours differ";
}

TEST(VolumeFormatIndependent, PythonBinvoxReaderDecodesTheSameVoxelsAndCentres) {
  for (const auto& [name, volume] : test_volumes()) {
    SCOPED_TRACE(name);
    const ToolRun run = run_tool("read_binvox.py", encode(volume, VolumeFormat::binvox));
    ASSERT_EQ(run.status, 0) << run.stdout_text;
    const auto summary = nlohmann::json::parse(run.stdout_text);
    const Grid& g = volume.grid();
    const std::int64_t d = std::max({g.dims.x, g.dims.y, g.dims.z});
    EXPECT_EQ(summary["version"], 1);
    EXPECT_EQ(summary["dim"], d);
    EXPECT_EQ(summary["nonzero_voxels"].get<std::uint64_t>(), volume.count());
    EXPECT_TRUE(run.voxels == voxel_bytes(volume, glm::i64vec3(d))) << "decoded voxels differ";
    if (volume.count() > 0) {
      // The binvox mapping of the file must put the voxel centre where voxd has it.
      const auto ijk = summary["first_set_voxel"].get<std::vector<std::int64_t>>();
      const glm::dvec3 centre = g.center(ijk[0], ijk[1], ijk[2]);
      for (int a = 0; a < 3; ++a)
        EXPECT_NEAR(summary["first_set_center"][static_cast<std::size_t>(a)].get<double>(), centre[a],
                    1e-9 * (1.0 + std::abs(centre[a])));
    }
  }
  const DenseVolume<std::uint8_t> u8 = random_u8_volume(make_grid({20, 9, 13}), 19);
  const ToolRun run = run_tool("read_binvox.py", binvox_u8(u8));
  ASSERT_EQ(run.status, 0) << run.stdout_text;
  EXPECT_EQ(nlohmann::json::parse(run.stdout_text)["version"], 2);
  Bytes expected;
  for (std::int64_t k = 0; k < 20; ++k)
    for (std::int64_t j = 0; j < 20; ++j)
      for (std::int64_t i = 0; i < 20; ++i) expected.push_back(j < 9 && k < 13 ? u8.at(i, j, k) : 0);
  EXPECT_TRUE(run.voxels == expected) << "decoded u8 voxels differ";
}

// ---------------------------------------------------------------- mutation --

// Random edits of a valid stream: the reader must either throw voxd::Error or
// return a volume that is self-consistent; anything else (crash, other
// exception, hang, sanitizer report) fails.
Bytes mutate(const Bytes& original, std::mt19937& rng) {
  Bytes b = original;
  const int edits = 1 + static_cast<int>(rng() % 4);
  for (int e = 0; e < edits && !b.empty(); ++e) {
    const std::size_t at = rng() % b.size();
    switch (rng() % 7) {
      case 0: b[at] ^= static_cast<std::uint8_t>(1u << (rng() % 8)); break;
      case 1: b[at] = static_cast<std::uint8_t>(rng()); break;
      case 2: b[at] = rng() % 2 ? 0xff : 0x00; break;
      case 3: b.resize(at); break;
      case 4: b.insert(b.begin() + static_cast<std::ptrdiff_t>(at), static_cast<std::uint8_t>(rng())); break;
      case 5: b.erase(b.begin() + static_cast<std::ptrdiff_t>(at)); break;
      case 6: {  // duplicate a short range, e.g. a whole block
        const std::size_t n = std::min<std::size_t>(1 + rng() % 16, b.size() - at);
        const Bytes piece(b.begin() + static_cast<std::ptrdiff_t>(at), b.begin() + static_cast<std::ptrdiff_t>(at + n));
        b.insert(b.begin() + static_cast<std::ptrdiff_t>(rng() % b.size()), piece.begin(), piece.end());
        break;
      }
    }
  }
  return b;
}

template <class Read, class Check>
void mutation_loop(const std::vector<Bytes>& seeds, int iterations, int min_accepted, const Read& read,
                   const Check& check) {
  std::mt19937 rng(2024);
  int accepted = 0, rejected = 0;
  for (int n = 0; n < iterations; ++n) {
    const Bytes input = mutate(seeds[static_cast<std::size_t>(n) % seeds.size()], rng);
    try {
      check(read(input));
      ++accepted;
    } catch (const Error&) {
      ++rejected;
    } catch (const std::exception& e) {
      FAIL() << "iteration " << n << ": non-voxd exception " << e.what();
    }
  }
  // Most mutations break a stream; some must survive, or the acceptance path
  // is not being exercised at all.
  EXPECT_GT(rejected, iterations / 2);
  EXPECT_GE(accepted, min_accepted);
  ::testing::Test::RecordProperty("accepted", accepted);
}

void check_bit_volume(const BitVolume& v) {
  const Grid& g = v.grid();
  ASSERT_TRUE(g.dims.x >= 1 && g.dims.y >= 1 && g.dims.z >= 1);
  ASSERT_LE(v.count(), g.voxel_count());
  if (g.dims.x % 64 != 0) {
    for (std::int64_t k = 0; k < g.dims.z; ++k) {
      for (std::int64_t j = 0; j < g.dims.y; ++j) {
        ASSERT_EQ(v.row(j, k)[v.row_words() - 1] >> (g.dims.x % 64), 0u);
      }
    }
  }
}

// The NRRD header's fields (the blank line ends it) and the bytes after it.
std::pair<std::map<std::string, std::string>, Bytes> split_nrrd(const Bytes& file) {
  const std::string text(file.begin(), file.end());
  const std::size_t end = text.find("\n\n");
  EXPECT_NE(end, std::string::npos);
  std::map<std::string, std::string> fields;
  std::istringstream lines(text.substr(0, end));
  for (std::string line; std::getline(lines, line);)
    if (auto colon = line.find(": "); colon != std::string::npos) fields[line.substr(0, colon)] = line.substr(colon + 2);
  return {fields, Bytes(file.begin() + static_cast<std::ptrdiff_t>(end + 2), file.end())};
}

Bytes gunzip(const Bytes& in) {
  z_stream z{};
  EXPECT_EQ(inflateInit2(&z, 15 + 16), Z_OK);
  Bytes out(1 << 20);
  z.next_in = const_cast<Bytef*>(in.data());
  z.avail_in = static_cast<uInt>(in.size());
  z.next_out = out.data();
  z.avail_out = static_cast<uInt>(out.size());
  EXPECT_EQ(inflate(&z, Z_FINISH), Z_STREAM_END);
  out.resize(z.total_out);
  EXPECT_EQ(z.avail_in, 0u) << "one gzip member, nothing after it";
  inflateEnd(&z);
  return out;
}

TEST(VolumeFormatNrrd, EveryValueTypeIsItsRawDataBehindAHeaderUncompressedOrGzip) {
  const Grid g = make_grid({13, 7, 5}, {1, 2, 3}, 0.5);
  const BitVolume bits = random_volume(g, 31);
  const DenseVolume<std::uint8_t> bytes = random_u8_volume(g, 32);
  const DenseVolume<float> floats = random_f32_volume(g, 33);
  struct Case {
    std::function<void(ByteSink&, NrrdEncoding)> write_nrrd;
    std::function<void(ByteSink&)> write_raw;
    const char* type;
  };
  const Case cases[] = {
      {[&](ByteSink& s, NrrdEncoding e) { write_nrrd(bits, "voxels", s, e); },
       [&](ByteSink& s) { write_raw(bits, RawPacking::bytes, s); }, "uchar"},
      {[&](ByteSink& s, NrrdEncoding e) { write_nrrd(bytes, "coverage", s, e); }, [&](ByteSink& s) { write_raw(bytes, s); },
       "uchar"},
      {[&](ByteSink& s, NrrdEncoding e) { write_nrrd(floats, "distance", s, e); }, [&](ByteSink& s) { write_raw(floats, s); },
       "float"},
  };
  for (const Case& c : cases) {
    VectorSink raw, plain, gz;
    c.write_raw(raw);
    c.write_nrrd(plain, NrrdEncoding::raw);
    c.write_nrrd(gz, NrrdEncoding::gzip);
    const auto [fields, data] = split_nrrd(plain.data);
    EXPECT_EQ(fields.at("type"), c.type);
    EXPECT_EQ(fields.at("sizes"), "13 7 5");
    EXPECT_EQ(fields.at("space origin"), "(1.25,2.25,3.25)");  // the first voxel's centre
    EXPECT_EQ(fields.at("encoding"), "raw");
    EXPECT_EQ(data, raw.data);
    const auto [gz_fields, gz_data] = split_nrrd(gz.data);
    EXPECT_EQ(gz_fields.at("encoding"), "gzip");
    EXPECT_EQ(gunzip(gz_data), raw.data);
    EXPECT_LT(gz_data.size(), raw.data.size());
  }
  // The value-volume dispatcher writes the same bytes with its options.
  VectorSink via_dispatch;
  encode_volume(ValueVolume(floats), VolumeFormat::nrrd, via_dispatch,
                EncodeOptions{RawPacking::bytes, NrrdEncoding::raw, "distance"});
  VectorSink direct;
  write_nrrd(floats, "distance", direct);
  EXPECT_EQ(via_dispatch.data, direct.data);
}

TEST(VolumeFormatValues, FormatsThatCannotHoldTheValuesAreRefusedWithWhatToAskFor) {
  const ValueVolume floats = random_f32_volume(make_grid({5, 4, 3}), 41);
  const ValueVolume bytes = random_u8_volume(make_grid({5, 4, 3}), 42);
  EXPECT_STREQ(value_type_name(floats), "f32");
  EXPECT_STREQ(value_type_name(bytes), "u8");
  EXPECT_EQ(byte_size(floats), 5u * 4 * 3 * 4);
  const auto binvox = format_refusal(floats, VolumeFormat::binvox, {});
  ASSERT_TRUE(binvox);
  EXPECT_NE(binvox->find("rle, raw or nrrd"), std::string::npos);
  EXPECT_FALSE(format_refusal(bytes, VolumeFormat::binvox, {}));
  EncodeOptions packed;
  packed.raw_packing = RawPacking::bits;
  EXPECT_TRUE(format_refusal(bytes, VolumeFormat::raw, packed));
  for (VolumeFormat f : {VolumeFormat::rle, VolumeFormat::raw, VolumeFormat::nrrd}) {
    EXPECT_FALSE(format_refusal(floats, f, {})) << to_string(f);
    VectorSink sink;
    encode_volume(floats, f, sink);
    EXPECT_FALSE(sink.data.empty());
  }
  VectorSink sink;
  EXPECT_EQ(error_code_of([&] { encode_volume(floats, VolumeFormat::binvox, sink); }), ErrorCode::invalid_argument);
  EXPECT_TRUE(sink.data.empty()) << "refused before writing";
  // u8 binvox through the dispatcher is the version-2 writer's output.
  VectorSink dispatched, direct;
  encode_volume(bytes, VolumeFormat::binvox, dispatched);
  write_binvox(std::get<DenseVolume<std::uint8_t>>(bytes), direct);
  EXPECT_EQ(dispatched.data, direct.data);
}

TEST(VolumeFormatMutation, RleStreams) {
  const std::vector<Bytes> seeds = {
      encode(random_volume(make_grid({13, 7, 5}, {1, 2, 3}, 0.5), 21), VolumeFormat::rle),
      encode(sphere_volume(make_grid({20, 20, 20})), VolumeFormat::rle),
      encode(BitVolume(make_grid({70, 2, 3})), VolumeFormat::rle),
  };
  mutation_loop(seeds, 3000, 1, [](const Bytes& b) { return read_rle_bits(b); },
                [](const BitVolume& v) {
                  check_bit_volume(v);
                  // Whatever was accepted must survive its own round trip.
                  expect_same_voxels(v, read_rle_bits(encode(v, VolumeFormat::rle)));
                });
  const std::vector<Bytes> f32_seeds = {rle_f32(random_f32_volume(make_grid({11, 6, 4}), 23))};
  mutation_loop(f32_seeds, 1500, 1, [](const Bytes& b) { return read_rle_f32(b); },
                [](const DenseVolume<float>& v) {
                  ASSERT_EQ(v.values().size(), v.grid().voxel_count());
                  const DenseVolume<float> back = read_rle_f32(rle_f32(v));
                  EXPECT_EQ(std::memcmp(back.values().data(), v.values().data(), v.values().size() * 4), 0);
                });
  const std::vector<Bytes> u8_seeds = {rle_u8(random_u8_volume(make_grid({11, 6, 4}), 22))};
  mutation_loop(u8_seeds, 1500, 1, [](const Bytes& b) { return read_rle_u8(b); },
                [](const DenseVolume<std::uint8_t>& v) {
                  ASSERT_EQ(v.values().size(), v.grid().voxel_count());
                  EXPECT_EQ(read_rle_u8(rle_u8(v)).values(), v.values());
                });
}

TEST(VolumeFormatMutation, BinvoxFiles) {
  const std::vector<Bytes> seeds = {
      encode(random_volume(make_grid({13, 7, 5}, {1, 2, 3}, 0.5), 23), VolumeFormat::binvox),
      encode(sphere_volume(make_grid({16, 16, 16})), VolumeFormat::binvox),
  };
  mutation_loop(seeds, 3000, 100, [](const Bytes& b) { return read_binvox(b); },
                [](const BitVolume& v) {
                  check_bit_volume(v);
                  expect_same_voxels(v, read_binvox(encode(v, VolumeFormat::binvox)));
                });
  const std::vector<Bytes> u8_seeds = {binvox_u8(random_u8_volume(make_grid({9, 8, 7}), 24))};
  mutation_loop(u8_seeds, 1000, 50, [](const Bytes& b) { return read_binvox_u8(b); },
                [](const DenseVolume<std::uint8_t>& v) { ASSERT_EQ(v.values().size(), v.grid().voxel_count()); });
}

void put_varint(Bytes& out, std::uint64_t v, bool padded) {
  while (v >= 0x80) {
    out.push_back(static_cast<std::uint8_t>(v | 0x80));
    v >>= 7;
  }
  if (padded) {  // non-minimal but valid: an extra continuation group of zeros
    out.push_back(static_cast<std::uint8_t>(v | 0x80));
    v = 0;
  }
  out.push_back(static_cast<std::uint8_t>(v));
}

// Streams built from the grammar of the spec with random runs (zero-length
// ones and non-minimal varints included), a few deliberately wrong: the
// reader must accept exactly the valid ones and decode them as the spec says.
// The mutation tests above mostly explore rejection; this explores acceptance.
TEST(VolumeFormatMutation, GeneratedRleStreams) {
  std::mt19937 rng(99);
  int valid_streams = 0;
  for (int n = 0; n < 2000; ++n) {
    const glm::i64vec3 dims(1 + rng() % 70, 1 + rng() % 4, 1 + rng() % 4);
    const auto slab_voxels = static_cast<std::uint64_t>(dims.x * dims.y);
    BitVolume expected(make_grid(dims));
    bool valid = true;
    Bytes blocks;
    for (std::int64_t k = 0; k < dims.z; ++k) {
      std::vector<std::uint64_t> runs;
      for (std::uint64_t covered = 0; covered < slab_voxels;) {
        const std::uint64_t left = slab_voxels - covered;
        const std::uint64_t run = rng() % 5 == 0 ? 0 : rng() % 4 == 0 ? left : 1 + rng() % std::min<std::uint64_t>(left, 40);
        runs.push_back(run);
        covered += run;
      }
      if (rng() % 40 == 0) runs.push_back(1 + rng() % 5);                  // covers too much
      if (rng() % 40 == 0 && runs.back() > 0) runs.back() -= 1;             // covers too little
      std::uint64_t position = 0;
      Bytes payload;
      for (std::size_t r = 0; r < runs.size(); ++r) {
        if (r % 2 == 1)
          for (std::uint64_t v = position; v < std::min(position + runs[r], slab_voxels); ++v)
            expected.set(static_cast<std::int64_t>(v % dims.x), static_cast<std::int64_t>(v / dims.x), k, true);
        position += runs[r];
        put_varint(payload, runs[r], rng() % 10 == 0);
      }
      valid = valid && position == slab_voxels;
      const bool wrong_index = rng() % 100 == 0;
      valid = valid && !wrong_index;
      blocks.push_back(0x53);
      put_varint(blocks, static_cast<std::uint64_t>(k + (wrong_index ? 1 : 0)), false);
      put_varint(blocks, payload.size(), false);
      blocks.insert(blocks.end(), payload.begin(), payload.end());
    }
    const bool wrong_count = rng() % 100 == 0;
    valid = valid && !wrong_count;
    blocks.push_back(0x45);
    put_varint(blocks, static_cast<std::uint64_t>(dims.z + (wrong_count ? 1 : 0)), false);

    const std::string header = "{\"dims\":[" + std::to_string(dims.x) + "," + std::to_string(dims.y) + "," +
                               std::to_string(dims.z) +
                               "],\"origin\":[0,0,0],\"voxel_size\":1,\"axis_order\":\"xyz\",\"value_type\":\"bit\"}";
    const Bytes stream = concat({rle_preamble(header), blocks});
    if (valid) {
      ++valid_streams;
      BitVolume decoded;
      ASSERT_NO_THROW(decoded = read_rle_bits(stream)) << "stream " << n;
      expect_same_voxels(expected, decoded);
      // Read as runs: each row's runs maximal and in order (a stored run
      // split by a 0-run of length 0, or going on into the next row, is
      // joined or cut), and the same voxels.
      BitVolume from_runs(make_grid(dims));
      std::int64_t next_layer = 0;
      ASSERT_NO_THROW(read_rle_run_slabs(stream, 1 + n % 3, [&](std::int64_t k0, const RunSlab& slab) {
        ASSERT_EQ(k0, next_layer);
        next_layer += slab.grid().dims.z;
        for (std::int64_t k = 0; k < slab.grid().dims.z; ++k)
          for (std::int64_t j = 0; j < dims.y; ++j) {
            const auto runs = slab.row(j, k);
            for (std::size_t r = 0; r < runs.size(); r += 2) {
              ASSERT_LT(runs[r], runs[r + 1]);
              ASSERT_LE(runs[r + 1], dims.x);
              if (r + 2 < runs.size()) {
                ASSERT_GT(runs[r + 2], runs[r + 1]) << "runs touch: not maximal";
              }
              for (std::uint32_t i = runs[r]; i < runs[r + 1]; ++i) from_runs.set(i, j, k0 + k, true);
            }
          }
      })) << "stream " << n;
      EXPECT_EQ(next_layer, dims.z);
      expect_same_voxels(expected, from_runs);
    } else {
      EXPECT_EQ(error_code_of([&] { read_rle_bits(stream); }), ErrorCode::malformed_input) << "stream " << n;
      EXPECT_EQ(error_code_of([&] { read_rle_run_slabs(stream, 2, [](std::int64_t, const RunSlab&) {}); }),
                ErrorCode::malformed_input)
          << "stream " << n;
    }
  }
  EXPECT_GT(valid_streams, 1000);
}

}  // namespace
}  // namespace voxd
