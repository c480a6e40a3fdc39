// Direct rendering of a signed distance field (voxd/analysis/sdf_render.h): a torus
// filling a 256^3 and a 512^3 grid, its field clamped to a 3-voxel band as
// signed_distance_field() leaves it, rendered from +z (rays across the
// slabs: strided reads) and +x (rays along the x rows), one pixel per voxel.
// The field is analytic so the bench measures the renderer alone.
// Counters: pixels of the image, and hits (pixels showing the part).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "voxd/parallel.h"
#include "voxd/analysis/sdf_render.h"

namespace voxd::bench {
namespace {

const DenseVolume<float>& torus_field(std::int64_t n) {
  static std::map<std::int64_t, DenseVolume<float>> cache;
  auto it = cache.find(n);
  if (it != cache.end()) return it->second;
  Grid g;
  g.dims = {n, n, n};
  g.voxel_size = 1.0;
  DenseVolume<float> f(g);
  const double c = 0.5 * static_cast<double>(n), major = 0.3 * static_cast<double>(n), minor = 0.12 * static_cast<double>(n);
  // The torus is tilted about x so no view sees only flat silhouettes.
  const double ca = std::cos(0.5), sa = std::sin(0.5);
  parallel_for(0, n, 4, 0, [&](std::int64_t k0, std::int64_t k1) {
    for (std::int64_t k = k0; k < k1; ++k)
      for (std::int64_t j = 0; j < n; ++j)
        for (std::int64_t i = 0; i < n; ++i) {
          const double x = static_cast<double>(i) + 0.5 - c, y0 = static_cast<double>(j) + 0.5 - c,
                       z0 = static_cast<double>(k) + 0.5 - c;
          const double y = ca * y0 - sa * z0, z = sa * y0 + ca * z0;
          const double ring = std::sqrt(x * x + y * y) - major;
          const double d = std::sqrt(ring * ring + z * z) - minor;
          f.at(i, j, k) = static_cast<float>(std::clamp(d, -3.0, 3.0));
        }
  });
  return cache.emplace(n, std::move(f)).first->second;
}

void run(benchmark::State& state, View view) {
  const DenseVolume<float>& f = torus_field(state.range(0));
  const SdfRenderInput in{&f, true, 1.0, "voxel"};
  std::size_t hits = 0, pixels = 0;
  for (auto _ : state) {
    const SdfRenderImage img = render_sdf(in, view);
    pixels = img.hit.size();
    hits = static_cast<std::size_t>(std::count_if(img.hit.begin(), img.hit.end(), [](const glm::dvec3& h) { return !std::isnan(h.x); }));
    benchmark::DoNotOptimize(img.image.pixels.data());
  }
  state.counters["pixels"] = static_cast<double>(pixels);
  state.counters["hits"] = static_cast<double>(hits);
}

void BM_SdfRenderTop(benchmark::State& state) { run(state, View{2, true}); }
BENCHMARK(BM_SdfRenderTop)->Arg(256)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_SdfRenderSide(benchmark::State& state) { run(state, View{0, true}); }
BENCHMARK(BM_SdfRenderSide)->Arg(256)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace voxd::bench
