// PNG stack writing: each layer is flipped into image rows (y descending),
// encoded into memory on a worker thread, and added to the ZIP in order, so
// only a few layers' PNGs are held at a time.
#include "voxd/encode/png_stack.h"

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "encode/ordered_pipeline.h"
#include "encode/volume_checks.h"
#include "voxd/error.h"
#include "voxd/encode/number_text.h"
#include "voxd/parallel.h"
#include "voxd/encode/png_image.h"
#include "voxd/encode/zip_archive.h"

namespace voxd {
namespace {

// Layers plus the manifest must fit the ZIP's 65535 entries.
constexpr std::int64_t kMaxLayers = 0xFFFF - 1;

void check_grid(const DenseVolume<Rgba8>& volume, const char* writer) {
  encode::require_voxels(volume, writer);
  const Grid& g = volume.grid();
  if (!std::isfinite(g.origin.x) || !std::isfinite(g.origin.y) || !std::isfinite(g.origin.z) ||
      !std::isfinite(g.voxel_size))
    throw Error(ErrorCode::invalid_argument, std::string(writer) + ": the grid origin and voxel size must be finite");
}

// Image rows top to bottom: y from dims.y - 1 down to 0.
std::vector<std::uint8_t> layer_pixels(const DenseVolume<Rgba8>& volume, std::int64_t k) {
  const auto nx = static_cast<std::size_t>(volume.grid().dims.x);
  const std::int64_t ny = volume.grid().dims.y;
  std::vector<std::uint8_t> pixels(nx * static_cast<std::size_t>(ny) * 4);
  std::uint8_t* out = pixels.data();
  for (std::int64_t j = ny - 1; j >= 0; --j) {
    const Rgba8* row = &volume.at(0, j, k);
    for (std::size_t i = 0; i < nx; ++i) {
      *out++ = row[i].r;
      *out++ = row[i].g;
      *out++ = row[i].b;
      *out++ = row[i].a;
    }
  }
  return pixels;
}

// `threads` for one large layer's bands: 1 where the layers themselves are
// spread over the cores; the bytes are the same either way.
void encode_layer(const DenseVolume<Rgba8>& volume, std::int64_t k, ByteSink& sink, int threads) {
  const Grid& g = volume.grid();
  const std::vector<PngText> text = {
      {"voxd:axis", "z"}, {"voxd:layer", std::to_string(k)}, {"voxd:voxel_size", number_text(g.voxel_size)}};
  // A stack is bulk output (hundreds of layers): fast compression.
  write_png_rgba8(static_cast<int>(g.dims.x), static_cast<int>(g.dims.y), layer_pixels(volume, k), text, sink,
                  PngCompression::fast, threads);
}

std::string manifest(const Grid& g) {
  return "{\"layers\": " + std::to_string(g.dims.z) + ", \"width\": " + std::to_string(g.dims.x) +
         ", \"height\": " + std::to_string(g.dims.y) + ", \"voxel_size\": " + number_text(g.voxel_size) +
         ", \"origin\": [" + number_text(g.origin.x) + ", " + number_text(g.origin.y) + ", " +
         number_text(g.origin.z) + "], \"axis\": \"z\", \"row_order\": \"y descending\"}\n";
}

}  // namespace

std::string png_layer_name(std::int64_t k) {
  char name[32];
  std::snprintf(name, sizeof name, "layer-%05lld.png", static_cast<long long>(k));
  return name;
}

void write_png_stack_zip(const DenseVolume<Rgba8>& volume, ByteSink& sink) {
  check_grid(volume, "PNG stack writer");
  const Grid& g = volume.grid();
  // Refused before the first byte, rather than when the ZIP fills up.
  if (g.dims.z > kMaxLayers)
    throw Error(ErrorCode::limit_exceeded, "PNG stack writer: " + std::to_string(g.dims.z) +
                                               " layers exceed the " + std::to_string(kMaxLayers) +
                                               " a ZIP archive without ZIP64 can hold (with the manifest)");
  ZipWriter zip(sink);
  const std::string text = manifest(g);
  zip.add("manifest.json", std::span(reinterpret_cast<const std::uint8_t*>(text.data()), text.size()), true);
  // PNG compression is most of the time: layers are encoded on all cores
  // and added to the archive in order, on this thread.
  const int threads = default_thread_count();
  std::vector<VectorSink> slots(static_cast<std::size_t>(2 * threads));
  encode::run_ordered_pipeline(
      g.dims.z, threads, slots.size(),
      [&](std::int64_t k, std::size_t slot) {
        slots[slot].data.clear();
        encode_layer(volume, k, slots[slot], 1);
      },
      [&](std::int64_t k, std::size_t slot) { zip.add(png_layer_name(k), slots[slot].data, false); });
  zip.finish();
}

void write_png_layer(const DenseVolume<Rgba8>& volume, std::int64_t k, ByteSink& sink) {
  check_grid(volume, "PNG layer writer");
  if (k < 0 || k >= volume.grid().dims.z)
    throw Error(ErrorCode::invalid_argument, "PNG layer writer: layer " + std::to_string(k) + " is outside 0.." +
                                                 std::to_string(volume.grid().dims.z - 1));
  encode_layer(volume, k, sink, 0);
}

}  // namespace voxd
