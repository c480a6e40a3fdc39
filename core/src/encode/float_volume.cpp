// Float volumes as raw float32 and as NRRD. (The f32 RLE writer lives with
// the other RLE writers in rle_writer.cpp.)
#include <bit>
#include <cstring>
#include <string>
#include <vector>

#include "encode/volume_checks.h"
#include "voxd/number_text.h"
#include "voxd/volume_format.h"

namespace voxd {
namespace {

// Slab by slab, little-endian whatever the machine.
void write_float_data(const DenseVolume<float>& volume, ByteSink& sink) {
  const std::size_t n = volume.slab_size();
  if constexpr (std::endian::native == std::endian::little) {
    for (std::int64_t k = 0; k < volume.grid().dims.z; ++k) sink.write(volume.slab(k), n * sizeof(float));
  } else {
    std::vector<std::uint8_t> bytes(n * sizeof(float));
    for (std::int64_t k = 0; k < volume.grid().dims.z; ++k) {
      const float* values = volume.slab(k);
      for (std::size_t i = 0; i < n; ++i) {
        const auto bits = std::bit_cast<std::uint32_t>(values[i]);
        for (int b = 0; b < 4; ++b) bytes[4 * i + b] = static_cast<std::uint8_t>(bits >> (8 * b));
      }
      sink.write(bytes.data(), bytes.size());
    }
  }
}

}  // namespace

void write_raw(const DenseVolume<float>& volume, ByteSink& sink) {
  encode::require_voxels(volume, "raw writer");
  write_float_data(volume, sink);
}

void write_nrrd(const DenseVolume<float>& volume, std::string_view content, ByteSink& sink) {
  encode::require_voxels(volume, "NRRD writer");
  const Grid& g = volume.grid();
  const double h = g.voxel_size;
  // NRRD samples are node-centred: the space origin is the first voxel's
  // centre, and each axis steps one voxel size.
  std::string header = "NRRD0004\n# written by voxd\n";
  std::string text(content);
  for (char& c : text)
    if (c == '\n' || c == '\r') c = ' ';
  header += "content: " + text + "\n";
  header += "type: float\ndimension: 3\n";
  header += "space dimension: 3\n";
  header += "sizes: " + std::to_string(g.dims.x) + " " + std::to_string(g.dims.y) + " " + std::to_string(g.dims.z) + "\n";
  header += "space directions: (" + number_text(h) + ",0,0) (0," + number_text(h) + ",0) (0,0," + number_text(h) + ")\n";
  header += "space origin: (" + number_text(g.origin.x + 0.5 * h) + "," + number_text(g.origin.y + 0.5 * h) + "," +
            number_text(g.origin.z + 0.5 * h) + ")\n";
  header += "kinds: domain domain domain\ncenterings: cell cell cell\nendian: little\nencoding: raw\n\n";
  sink.write(header.data(), header.size());
  write_float_data(volume, sink);
}

}  // namespace voxd
