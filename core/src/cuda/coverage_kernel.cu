// Grey coverage on a CUDA GPU: the passes of core/src/voxelize/
// coverage_kernels.h, the code the CPU runs too, built with -fmad=false
// (core/CMakeLists.txt) so that every float equals the CPU's.
//  - crossings: a block's warps share out the triangles binned to its row,
//    the 32 lanes of a warp one triangle's (column, ray) pairs; counted per
//    column, then, at offsets the host sums, written;
//  - columns: one thread a column sorts, pairs and integrates its crossings.
#include <cuda_runtime.h>

#include <algorithm>
#include <vector>

#include "cuda/cuda_support.h"
#include "voxd/compute_device.h"
#include "voxd/error.h"
#include "voxelize/coverage_device.h"

namespace voxd::detail {
namespace {

using cuda::check;
using cuda::DeviceBuffer;

constexpr int kBlock = 256;
constexpr int kWarpsPerBlock = kBlock / 32;

// What the crossing kernels read.
struct SceneView {
  const std::int64_t* vertices;
  const std::uint32_t* triangles;
  const std::uint32_t* bin_offsets;
  const std::uint32_t* bin_triangles;
  std::int64_t rows_per_chunk;
  std::int64_t ny;
};

// emit(row, j, ray, x) for every crossing of rows [k0, k0 + layers), row
// counted from k0: blocks (x) share a row's triangles by warps, rows go by
// blocks (y).
template <typename Emit>
__device__ void for_each_crossing(const SceneView& s, const CoverageRayPattern& rays, std::int64_t k0,
                                  std::int64_t layers, const Emit& emit) {
  const int lane = static_cast<int>(threadIdx.x % 32);
  const std::int64_t warp = static_cast<std::int64_t>(blockIdx.x) * kWarpsPerBlock + threadIdx.x / 32;
  const std::int64_t warps = static_cast<std::int64_t>(gridDim.x) * kWarpsPerBlock;
  for (std::int64_t row = blockIdx.y; row < layers; row += gridDim.y) {
    const std::int64_t k = k0 + row;
    const auto chunk = static_cast<std::size_t>(k / s.rows_per_chunk);
    for (std::int64_t i = s.bin_offsets[chunk] + warp; i < s.bin_offsets[chunk + 1]; i += warps) {
      const std::uint32_t* corner = s.triangles + 3 * static_cast<std::size_t>(s.bin_triangles[i]);
      cross_row_triangle(s.vertices + 3 * static_cast<std::size_t>(corner[0]),
                         s.vertices + 3 * static_cast<std::size_t>(corner[1]),
                         s.vertices + 3 * static_cast<std::size_t>(corner[2]), k, s.ny, rays, lane, 32,
                         [&](std::int64_t j, int ray, double x) { emit(row, j, ray, x); });
    }
  }
}

__global__ void count_kernel(SceneView s, CoverageRayPattern rays, std::int64_t k0, std::int64_t layers,
                             std::uint32_t* counts) {
  for_each_crossing(s, rays, k0, layers, [&](std::int64_t row, std::int64_t j, int, double) {
    atomicAdd(counts + row * s.ny + j, 1u);
  });
}

// cursors: zero on entry, each column's count on exit.
__global__ void write_kernel(SceneView s, CoverageRayPattern rays, std::int64_t k0, std::int64_t layers,
                             const std::uint64_t* offsets, std::uint32_t* cursors, ColumnEntry* entries) {
  for_each_crossing(s, rays, k0, layers, [&](std::int64_t row, std::int64_t j, int ray, double x) {
    const std::int64_t c = row * s.ny + j;
    const std::uint32_t slot = atomicAdd(cursors + c, 1u);
    entries[offsets[c] + slot] = ColumnEntry{x, ray, 0.0f};
  });
}

__global__ void column_kernel(CoverageColumnParams params, std::int64_t columns, const std::uint64_t* offsets,
                              ColumnEntry* entries, float* out) {
  const std::int64_t stride = static_cast<std::int64_t>(gridDim.x) * blockDim.x;
  for (std::int64_t c = static_cast<std::int64_t>(blockIdx.x) * blockDim.x + threadIdx.x; c < columns; c += stride)
    fill_coverage_column(entries + offsets[c], static_cast<std::int64_t>(offsets[c + 1] - offsets[c]), params,
                         out + c * params.nx);
}

class CudaCoverageDevice final : public CoverageSlabDevice {
 public:
  void begin(const CoverageScene& scene, std::int64_t max_layers, std::uint64_t crossing_room) override {
    room_ = crossing_room;
    columns_ = scene.columns;
    rays_ = scene.rays;
    vertices_.allocate(scene.vertices.size(), "allocation of the mesh's vertices");
    triangles_.allocate(scene.triangles.size(), "allocation of the mesh's triangles");
    bin_offsets_.allocate(scene.bin_offsets.size(), "allocation of the triangles' bins");
    bin_triangles_.allocate(scene.bin_triangles.size(), "allocation of the triangles' bins");
    const auto layer_columns = static_cast<std::size_t>(max_layers * columns_.ny);
    counts_.allocate(layer_columns, "allocation of the column counters");
    offsets_.allocate(layer_columns + 1, "allocation of the column offsets");
    out_.allocate(layer_columns * static_cast<std::size_t>(columns_.nx), "allocation of the coverages' slab");
    memory_.sample();
    stream_.timed(false, "copy of the mesh", [&] {
      vertices_.upload(scene.vertices.data(), scene.vertices.size(), stream_.get(), "copy of the vertices");
      triangles_.upload(scene.triangles.data(), scene.triangles.size(), stream_.get(), "copy of the triangles");
      bin_offsets_.upload(scene.bin_offsets.data(), scene.bin_offsets.size(), stream_.get(), "copy of the bins");
      bin_triangles_.upload(scene.bin_triangles.data(), scene.bin_triangles.size(), stream_.get(), "copy of the bins");
    });
    view_ = {vertices_.data, triangles_.data, bin_offsets_.data, bin_triangles_.data, scene.rows_per_chunk,
             columns_.ny};
    // Enough warps for the fullest row's triangles, a warp each.
    std::uint32_t fullest = 0;
    for (std::size_t c = 0; c + 1 < scene.bin_offsets.size(); ++c)
      fullest = std::max(fullest, scene.bin_offsets[c + 1] - scene.bin_offsets[c]);
    blocks_x_ = static_cast<unsigned>(std::clamp<std::uint32_t>((fullest + kWarpsPerBlock - 1) / kWarpsPerBlock, 1, 4096));
  }

  void count(std::int64_t k0, std::int64_t layers, std::uint32_t* counts) override {
    const auto columns = static_cast<std::size_t>(layers * columns_.ny);
    const dim3 grid(blocks_x_, static_cast<unsigned>(std::min<std::int64_t>(layers, 65535)));
    stream_.timed(true, "the crossings' count", [&] {
      check(cudaMemsetAsync(counts_.data, 0, columns * sizeof(std::uint32_t), stream_.get()), "clearing the counters");
      count_kernel<<<grid, kBlock, 0, stream_.get()>>>(view_, rays_, k0, layers, counts_.data);
    });
    stream_.timed(false, "copy of the counts", [&] {
      check(cudaMemcpyAsync(counts, counts_.data, columns * sizeof(std::uint32_t), cudaMemcpyDeviceToHost,
                            stream_.get()),
            "copy of the counts");
    });
  }

  void fill(std::int64_t k0, std::int64_t layers, const std::uint64_t* offsets, float* out) override {
    const std::int64_t columns = layers * columns_.ny;
    const std::uint64_t total = offsets[columns];
    if (total > room_) throw std::logic_error("coverage: a fill past the crossings' room");
    // Grown by half again (within the room), so that rows of slowly rising
    // counts do not reallocate every pass.
    if (total > entries_.capacity)
      entries_.reserve(static_cast<std::size_t>(std::min<std::uint64_t>(room_, std::max<std::uint64_t>(total, entries_.capacity * 3 / 2))),
                       "allocation of the crossings");
    memory_.sample();
    stream_.timed(false, "copy of the offsets", [&] {
      offsets_.upload(offsets, static_cast<std::size_t>(columns) + 1, stream_.get(), "copy of the offsets");
    });
    const dim3 grid(blocks_x_, static_cast<unsigned>(std::min<std::int64_t>(layers, 65535)));
    const std::size_t values = static_cast<std::size_t>(columns) * static_cast<std::size_t>(columns_.nx);
    stream_.timed(true, "the coverage kernels", [&] {
      check(cudaMemsetAsync(counts_.data, 0, static_cast<std::size_t>(columns) * sizeof(std::uint32_t), stream_.get()),
            "clearing the counters");
      write_kernel<<<grid, kBlock, 0, stream_.get()>>>(view_, rays_, k0, layers, offsets_.data, counts_.data,
                                                       entries_.data);
      check(cudaMemsetAsync(out_.data, 0, values * sizeof(float), stream_.get()), "clearing the slab");
      const auto blocks = static_cast<unsigned>(std::min<std::int64_t>((columns + kBlock - 1) / kBlock, 1 << 20));
      column_kernel<<<blocks, kBlock, 0, stream_.get()>>>(columns_, columns, offsets_.data, entries_.data, out_.data);
    });
    stream_.timed(false, "copy of the coverages", [&] {
      check(cudaMemcpyAsync(out, out_.data, values * sizeof(float), cudaMemcpyDeviceToHost, stream_.get()),
            "copy of the coverages");
    });
  }

  double kernel_ms() const override { return stream_.kernel_ms(); }
  double copy_ms() const override { return stream_.copy_ms(); }
  std::uint64_t measured_bytes() const override { return memory_.peak(); }

 private:
  cuda::MemoryWatch memory_;  // first: the free memory before any allocation
  cuda::TimedStream stream_;
  CoverageColumnParams columns_;
  CoverageRayPattern rays_;
  DeviceBuffer<std::int64_t> vertices_;
  DeviceBuffer<std::uint32_t> triangles_, bin_offsets_, bin_triangles_, counts_;
  DeviceBuffer<std::uint64_t> offsets_;
  DeviceBuffer<float> out_;
  DeviceBuffer<ColumnEntry> entries_;
  SceneView view_{};
  std::uint64_t room_ = 0;
  unsigned blocks_x_ = 1;
};

}  // namespace

std::unique_ptr<CoverageSlabDevice> make_cuda_coverage_device(std::uint64_t& budget) {
  if (const std::string& why = cuda_unavailable_reason(); !why.empty()) throw Error(ErrorCode::invalid_argument, why);
  cuda::select_gpu(budget);
  return std::make_unique<CudaCoverageDevice>();
}

}  // namespace voxd::detail
