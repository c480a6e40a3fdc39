// Value volumes as raw data: float32 little-endian, bytes as they are. (The
// RLE writers live in rle_writer.cpp, NRRD, which wraps this data, in nrrd.cpp.)
#include <bit>
#include <cstring>
#include <string>
#include <vector>

#include "encode/volume_checks.h"
#include "voxd/encode/volume_format.h"

namespace voxd {
namespace {

// Slab by slab, little-endian whatever the machine, each value times
// `scale` (a unit's) in a slab's buffer rather than in a copy of the volume.
void write_float_data(const DenseVolume<float>& volume, ByteSink& sink, float scale) {
  const std::size_t n = volume.slab_size();
  if (std::endian::native == std::endian::little && scale == 1.0f) {
    for (std::int64_t k = 0; k < volume.grid().dims.z; ++k) sink.write(volume.slab(k), n * sizeof(float));
  } else {
    std::vector<std::uint8_t> bytes(n * sizeof(float));
    for (std::int64_t k = 0; k < volume.grid().dims.z; ++k) {
      const float* values = volume.slab(k);
      for (std::size_t i = 0; i < n; ++i) {
        const auto bits = std::bit_cast<std::uint32_t>(values[i] * scale);
        for (int b = 0; b < 4; ++b) bytes[4 * i + b] = static_cast<std::uint8_t>(bits >> (8 * b));
      }
      sink.write(bytes.data(), bytes.size());
    }
  }
}

}  // namespace

void write_raw(const DenseVolume<std::uint8_t>& volume, ByteSink& sink) {
  encode::require_voxels(volume, "raw writer");
  for (std::int64_t k = 0; k < volume.grid().dims.z; ++k) sink.write(volume.slab(k), volume.slab_size());
}

void write_raw(const DenseVolume<Rgba8>& volume, ByteSink& sink) {
  encode::require_voxels(volume, "raw writer");
  static_assert(sizeof(Rgba8) == 4, "r, g, b, a bytes in that order, no padding");
  for (std::int64_t k = 0; k < volume.grid().dims.z; ++k) sink.write(volume.slab(k), volume.slab_size() * sizeof(Rgba8));
}

void write_raw(const DenseVolume<float>& volume, ByteSink& sink, float scale) {
  encode::require_voxels(volume, "raw writer");
  write_float_data(volume, sink, scale);
}

}  // namespace voxd
