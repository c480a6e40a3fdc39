#include "voxd/voxelize/streamed.h"

#include <algorithm>
#include <numeric>
#include <optional>

#include "voxd/error.h"
#include "voxd/parallel.h"
#include "voxelize/layer_range.h"
#include "voxelize/parity_voxelizer.h"
#include "voxelize/surface_voxelizer.h"

namespace voxd {
namespace {

std::uint64_t layer_bytes(const Grid& grid) { return bit_volume_bytes({grid.dims.x, grid.dims.y, 1}); }

}  // namespace

namespace detail {

LayerChunks layer_chunks(const Grid& grid, LayerRange range, std::int64_t wanted) {
  const std::int64_t nz = grid.dims.z;
  LayerChunks chunks;
  chunks.first = range.begin;
  chunks.end = range.end < 0 ? nz : range.end;
  if (chunks.first < 0 || chunks.first >= chunks.end || chunks.end > nz)
    throw Error(ErrorCode::invalid_argument, "layers " + std::to_string(chunks.first) + ".." + std::to_string(chunks.end) +
                                                 " are not a part of a grid of " + std::to_string(nz) + " layers");
  chunks.per_chunk = std::gcd(std::gcd(std::max<std::int64_t>(1, wanted), chunks.first), chunks.end == nz ? 0 : chunks.end);
  return chunks;
}

}  // namespace detail

bool can_stream(const VoxelizeOptions& options) {
  return options.mode == VoxelMode::surface || options.inside == InsideTest::parity;
}

std::int64_t streamed_slab_layers(const Grid& grid, std::uint64_t slab_bytes) {
  const std::uint64_t per_layer = std::max<std::uint64_t>(layer_bytes(grid), 1);
  return std::clamp<std::int64_t>(static_cast<std::int64_t>(slab_bytes / per_layer), 1, std::max<std::int64_t>(grid.dims.z, 1));
}

void voxelize_streamed(const Mesh& mesh, const Grid& grid, const VoxelizeOptions& options, std::int64_t slab_layers,
                       const BitSlabConsumer& consume, JobControl* control, LayerRange range) {
  if (!can_stream(options))
    throw Error(ErrorCode::invalid_argument, std::string("the ") + to_string(options.inside) +
                                                 " inside test needs the whole grid; only parity streams slab by slab");
  const int threads = options.threads > 0 ? options.threads : default_thread_count();
  // Chunks of a few rows, so each slab has work for every thread; a slab is
  // a whole number of chunks, and so are the range's ends (but the grid's
  // last layer): a chunk never reaches out of the slab it fills.
  const std::int64_t nz = grid.dims.z;
  const std::int64_t requested = range.end < 0 ? nz - range.begin : range.end - range.begin;
  const std::int64_t layers_wanted = std::max<std::int64_t>(1, std::min(slab_layers, requested));
  const detail::LayerChunks chunks = detail::layer_chunks(grid, range, std::max<std::int64_t>(1, layers_wanted / (4 * threads)));
  if (grid.voxel_count() == 0) return;
  const std::int64_t first = chunks.first, end = chunks.end, per_chunk = chunks.per_chunk;
  const std::int64_t layers = std::min(end - first, (layers_wanted + per_chunk - 1) / per_chunk * per_chunk);

  std::optional<detail::ParityVoxelizer> parity;
  std::optional<detail::SurfaceVoxelizer> surface;
  if (options.mode != VoxelMode::surface) parity.emplace(mesh, grid, 0, threads, per_chunk);
  if (options.mode != VoxelMode::solid) surface.emplace(mesh, grid, threads, per_chunk);

  const std::int64_t slabs = (end - first + layers - 1) / layers;
  for (std::int64_t s = 0; s < slabs; ++s) {
    if (control) control->check_cancelled();
    const std::int64_t k0 = first + s * layers, n = std::min(layers, end - k0);
    // A fresh slab comes zeroed from the OS (only the touched pages cost);
    // the last, shorter one is a slab of its own size.
    BitVolume slab(slab_grid(grid, k0, n));
    const std::int64_t c0 = k0 / per_chunk, c1 = (k0 + n + per_chunk - 1) / per_chunk;
    parallel_for(c0, c1, 1, threads, [&](std::int64_t a, std::int64_t b) {
      for (std::int64_t c = a; c < b; ++c) {
        if (control) control->check_cancelled();
        if (parity) parity->fill_chunk(c, slab, k0);
        if (surface) surface->fill_chunk(c, slab, k0);
      }
    });
    consume(k0, slab);
    // By layers, not slabs: the last, shorter slab counts for what it is.
    if (control) control->set_progress(static_cast<double>(k0 + n - first) / static_cast<double>(end - first));
  }
}

}  // namespace voxd
