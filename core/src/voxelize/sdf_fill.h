#pragma once
// The full field's values beyond the band, from exact nearest-triangle
// queries (any index with TriangleTree's nearest(): the oriented-box tree of
// sdf_tree.h, or Embree's BVH in sdf_embree.cpp), shared by the engine and
// the Embree tuning path that only the tests and benchmarks link.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>

#include "analysis/progress_span.h"
#include "voxd/dense_volume.h"
#include "voxd/grid.h"
#include "voxd/mesh.h"
#include "voxd/parallel.h"
#include "voxelize/sdf_band.h"
#include "voxelize/sdf_triangle.h"

namespace voxd::sdf {

template <class Nearest>
void fill_beyond_band(const Nearest& tree, const Grid& g, const BandSetup& s, float clamped, int threads,
                      DenseVolume<float>& values, const detail::ProgressSpan& queries) {
  const std::int64_t nx = g.dims.x, ny = g.dims.y, rows = ny * g.dims.z;
  std::atomic<std::int64_t> done{0};
  parallel_for(0, rows, std::max<std::int64_t>(1, rows / (threads * 64)), threads, [&](std::int64_t r0, std::int64_t r1) {
    for (std::int64_t r = r0; r < r1; ++r) {
      queries.check_cancelled();
      const std::int64_t j = r % ny, k = r / ny;
      float* row = values.slab(k) + j * nx;
      const double cy = centre_coordinate(g, 1, j), cz = centre_coordinate(g, 2, k);
      // The previous voxel's distance bounds this one's (d is 1-Lipschitz),
      // and its nearest triangle is usually this one's too.
      double previous = -1.0;
      std::uint32_t hint = Nearest::kNone;
      for (std::int64_t i = 0; i < nx; ++i) {
        if ((i & 255) == 255) queries.check_cancelled();
        if (row[i] < clamped) {  // exact from the band
          previous = static_cast<double>(row[i]) * s.to_model;
          continue;
        }
        const dvec3 p(centre_coordinate(g, 0, i), cy, cz);
        // The margin covers the float rounding of band values and of the
        // centres' spacing.
        const double bound = previous >= 0.0 ? (previous + g.voxel_size) * (1.0 + 1e-6) : kInfinity;
        typename Nearest::Hit hit = tree.nearest(p, bound * bound, hint);
        if (hit.triangle == Nearest::kNone) hit = tree.nearest(p, kInfinity, Nearest::kNone);
        if (hit.triangle == Nearest::kNone) continue;  // no triangles at all: stays clamped
        previous = std::sqrt(hit.d2);
        hint = hit.triangle;
        row[i] = static_cast<float>(previous * s.to_output);
      }
    }
    queries.report(static_cast<double>(done.fetch_add(r1 - r0) + (r1 - r0)) / static_cast<double>(rows));
  });
  queries.report(1.0);
}


// The Embree path of SdfTuning::Nearest::embree: queries the whole `rest`
// of the progress span. Set when voxd_sdf_embree (sdf_embree.cpp) is linked
// in; null otherwise.
using FillBeyondBand = void (*)(const Mesh& mesh, const Grid& g, const BandSetup& s, float clamped, int threads,
                                DenseVolume<float>& values, const detail::ProgressSpan& rest);
extern FillBeyondBand embree_fill_beyond_band;

}  // namespace voxd::sdf
