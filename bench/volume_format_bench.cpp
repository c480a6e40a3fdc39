// Encoder and decoder throughput on a solid sphere (the typical voxelizer
// output: long runs, ~2 transitions per row) and on random bits (worst case:
// a transition every other voxel); and the meshes of a result
// (GET /v1/jobs/{id}/volume?format=stl|ply|glb): the sphere's voxel surface
// made, then written as each mesh format.
// And a radiograph-sized PNG written on 1 to 16 threads.
//   ./build/bench/volume_format_bench --benchmark_filter=Sphere
#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <span>
#include <vector>

#include <benchmark/benchmark.h>

#include "voxd/byte_source.h"
#include "voxd/encode/mesh_export.h"
#include "voxd/encode/png_image.h"
#include "voxd/encode/rle_slabs.h"
#include "voxd/encode/volume_format.h"
#include "voxd/encode/volume_surface.h"

namespace {

using voxd::BitVolume;
using voxd::Grid;

// Counts bytes and drops them, so the benchmark measures the encoder alone.
class CountingSink final : public voxd::ByteSink {
 public:
  using ByteSink::write;
  void write(std::span<const std::uint8_t> bytes) override { size += bytes.size(); }
  std::size_t size = 0;
};

Grid cube_grid(std::int64_t n) {
  Grid g;
  g.dims = glm::i64vec3(n);
  g.voxel_size = 1.0 / static_cast<double>(n);
  return g;
}

// Solid sphere of radius 0.45 n in an n^3 grid, filled row by row.
const BitVolume& sphere(std::int64_t n) {
  static std::map<std::int64_t, std::unique_ptr<BitVolume>> cache;
  auto& slot = cache[n];
  if (slot) return *slot;
  slot = std::make_unique<BitVolume>(cube_grid(n));
  const double c = 0.5 * static_cast<double>(n), r = 0.45 * static_cast<double>(n);
  for (std::int64_t k = 0; k < n; ++k)
    for (std::int64_t j = 0; j < n; ++j) {
      const double dy = static_cast<double>(j) + 0.5 - c, dz = static_cast<double>(k) + 0.5 - c;
      const double h2 = r * r - dy * dy - dz * dz;
      if (h2 < 0) continue;
      const double h = std::sqrt(h2);
      const auto i0 = std::max<std::int64_t>(0, static_cast<std::int64_t>(std::ceil(c - h - 0.5)));
      const auto i1 = std::min<std::int64_t>(n, static_cast<std::int64_t>(std::floor(c + h - 0.5)) + 1);
      for (std::int64_t i = i0; i < i1; ++i) slot->set(i, j, k, true);
    }
  return *slot;
}

const BitVolume& random_bits(std::int64_t n) {
  static std::map<std::int64_t, std::unique_ptr<BitVolume>> cache;
  auto& slot = cache[n];
  if (slot) return *slot;
  slot = std::make_unique<BitVolume>(cube_grid(n));
  std::mt19937_64 rng(1);
  const std::int64_t mask_bits = n % 64;
  for (std::int64_t k = 0; k < n; ++k)
    for (std::int64_t j = 0; j < n; ++j)
      for (std::int64_t w = 0; w < slot->row_words(); ++w) {
        std::uint64_t v = rng();
        if (w == slot->row_words() - 1 && mask_bits) v &= (std::uint64_t{1} << mask_bits) - 1;
        slot->row(j, k)[w] = v;
      }
  return *slot;
}

void encode_bench(benchmark::State& state, const BitVolume& volume, voxd::VolumeFormat format,
                  voxd::RawPacking packing = voxd::RawPacking::bytes) {
  voxd::EncodeOptions options;
  options.raw_packing = packing;
  std::size_t bytes = 0;
  for (auto _ : state) {
    CountingSink sink;
    voxd::encode_volume(volume, format, sink, options);
    bytes = sink.size;
  }
  state.counters["output_MiB"] = static_cast<double>(bytes) / (1 << 20);
  state.counters["voxels/s"] = benchmark::Counter(static_cast<double>(volume.grid().voxel_count()),
                                                  benchmark::Counter::kIsIterationInvariantRate);
}

void BM_RleEncodeSphere(benchmark::State& s) { encode_bench(s, sphere(s.range(0)), voxd::VolumeFormat::rle); }
void BM_BinvoxEncodeSphere(benchmark::State& s) { encode_bench(s, sphere(s.range(0)), voxd::VolumeFormat::binvox); }
void BM_RawBitsEncodeSphere(benchmark::State& s) {
  encode_bench(s, sphere(s.range(0)), voxd::VolumeFormat::raw, voxd::RawPacking::bits);
}
void BM_RawBytesEncodeSphere(benchmark::State& s) { encode_bench(s, sphere(s.range(0)), voxd::VolumeFormat::raw); }
void BM_RleEncodeRandom(benchmark::State& s) { encode_bench(s, random_bits(s.range(0)), voxd::VolumeFormat::rle); }
void BM_BinvoxEncodeRandom(benchmark::State& s) {
  encode_bench(s, random_bits(s.range(0)), voxd::VolumeFormat::binvox);
}

void BM_RleDecodeSphere(benchmark::State& s) {
  voxd::VectorSink sink;
  voxd::write_rle(sphere(s.range(0)), sink);
  voxd::ReadLimits limits;
  limits.max_volume_bytes = std::uint64_t{1} << 34;
  for (auto _ : s) benchmark::DoNotOptimize(voxd::read_rle_bits(sink.data, limits));
}

void BM_BinvoxDecodeSphere(benchmark::State& s) {
  voxd::VectorSink sink;
  voxd::write_binvox(sphere(s.range(0)), sink);
  for (auto _ : s) benchmark::DoNotOptimize(voxd::read_binvox(sink.data));
}

// A stored result replayed slab by slab (voxd/encode/rle_slabs.h), as a
// streamed job's /volume and analyses do: from memory (a mapped file), and
// from a source that hands out 1 MiB at a time and is not in memory (the
// Redis store's slices), to see what the buffered window costs.
class SliceSource final : public voxd::ByteSource {
 public:
  explicit SliceSource(std::span<const std::uint8_t> data) : data_(data) {}
  std::size_t read(std::uint8_t* out, std::size_t size) override {
    const std::size_t n = std::min({size, std::size_t{1} << 20, data_.size() - at_});
    std::copy_n(data_.data() + at_, n, out);
    at_ += n;
    return n;
  }

 private:
  std::span<const std::uint8_t> data_;
  std::size_t at_ = 0;
};

void replay_bench(benchmark::State& state, const BitVolume& volume, bool sliced) {
  voxd::VectorSink sink;
  voxd::write_rle(volume, sink);
  std::uint64_t filled = 0;
  for (auto _ : state) {
    filled = 0;
    auto count = [&](std::int64_t, const BitVolume& slab) { filled += slab.count(); };
    if (sliced) {
      SliceSource source(sink.data);
      voxd::read_rle_bit_slabs(source, 16, count);
    } else {
      voxd::read_rle_bit_slabs(sink.data, 16, count);
    }
  }
  benchmark::DoNotOptimize(filled);
  state.counters["rle_MiB"] = static_cast<double>(sink.data.size()) / (1 << 20);
  state.counters["voxels/s"] = benchmark::Counter(static_cast<double>(volume.grid().voxel_count()),
                                                  benchmark::Counter::kIsIterationInvariantRate);
}

void BM_RleReplaySphereFromMemory(benchmark::State& s) { replay_bench(s, sphere(s.range(0)), false); }
void BM_RleReplaySphereFromSlices(benchmark::State& s) { replay_bench(s, sphere(s.range(0)), true); }
void BM_RleReplayRandomFromMemory(benchmark::State& s) { replay_bench(s, random_bits(s.range(0)), false); }
void BM_RleReplayRandomFromSlices(benchmark::State& s) { replay_bench(s, random_bits(s.range(0)), true); }

void BM_VoxelSurfaceSphere(benchmark::State& state) {
  const BitVolume& volume = sphere(state.range(0));
  std::size_t triangles = 0;
  for (auto _ : state) {
    const voxd::Mesh mesh = voxd::voxel_surface(volume);
    triangles = mesh.triangles.size();
  }
  state.counters["triangles"] = static_cast<double>(triangles);
}

using MeshWriter = void (*)(const voxd::Mesh&, const std::string&, voxd::ByteSink&);
void mesh_write_bench(benchmark::State& state, MeshWriter write) {
  const voxd::Mesh mesh = voxd::voxel_surface(sphere(state.range(0)));
  std::size_t bytes = 0;
  for (auto _ : state) {
    CountingSink sink;
    write(mesh, "voxel surface", sink);
    bytes = sink.size;
  }
  state.counters["output_MiB"] = static_cast<double>(bytes) / (1 << 20);
}
void BM_MeshStlSphere(benchmark::State& s) { mesh_write_bench(s, voxd::write_mesh_stl); }
void BM_MeshPlySphere(benchmark::State& s) { mesh_write_bench(s, voxd::write_mesh_ply); }
void BM_MeshGlbSphere(benchmark::State& s) { mesh_write_bench(s, voxd::write_mesh_glb); }

// A radiograph-sized 16-bit PNG (a sphere's chord lengths over a side x
// side image, as a radiograph of a ball reads) written on `threads`
// threads: from four bands up the rows are filtered and deflated in bands
// (core/src/encode/png_bands.h). Args: side, threads.
void BM_PngGrey16(benchmark::State& state) {
  const auto side = static_cast<int>(state.range(0));
  std::vector<std::uint32_t> values(static_cast<std::size_t>(side) * static_cast<std::size_t>(side));
  const double r = 0.45 * side;
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x) {
      const double dx = x - side / 2.0, dy = y - side / 2.0, d2 = r * r - dx * dx - dy * dy;
      values[static_cast<std::size_t>(y) * static_cast<std::size_t>(side) + static_cast<std::size_t>(x)] =
          d2 > 0 ? static_cast<std::uint32_t>(2 * std::sqrt(d2)) : 0;
    }
  std::size_t bytes = 0;
  for (auto _ : state) {
    CountingSink sink;
    voxd::write_png_grey16(side, side, values, {}, {}, sink, static_cast<int>(state.range(1)));
    bytes = sink.size;
  }
  state.counters["png_MiB"] = static_cast<double>(bytes) / (1 << 20);
  state.counters["pixels/s"] = benchmark::Counter(static_cast<double>(values.size()),
                                                  benchmark::Counter::kIsIterationInvariantRate);
}

}  // namespace

BENCHMARK(BM_RleEncodeSphere)->Arg(256)->Arg(512)->Arg(1024)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_BinvoxEncodeSphere)->Arg(256)->Arg(512)->Arg(1024)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RawBitsEncodeSphere)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RawBytesEncodeSphere)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RleEncodeRandom)->Arg(256)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_BinvoxEncodeRandom)->Arg(256)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RleDecodeSphere)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_BinvoxDecodeSphere)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RleReplaySphereFromMemory)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RleReplaySphereFromSlices)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RleReplayRandomFromMemory)->Arg(256)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RleReplayRandomFromSlices)->Arg(256)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_VoxelSurfaceSphere)->Arg(256)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_MeshStlSphere)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_MeshPlySphere)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_MeshGlbSphere)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_PngGrey16)
    ->ArgsProduct({{4096}, {1, 2, 16}})
    ->ArgNames({"side", "threads"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
