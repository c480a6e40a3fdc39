// Wall thickness against the mesh's own ray thickness (tests/support/
// ray_thickness.h) on generated curved parts with exact walls: the table
// of issue #35, for measuring the analysis before and after a change.
//   build/bench/wall_accuracy [voxel_size=0.05] [points=2000]
// Prints, per part: the wall, the ray thickness's min/mean, the map's
// min/mean at the same surface points (2 voxels or more from sharp edges),
// the share of points within ±1 and ±1.5 voxels of the ray, the 1st, 50th
// and 99th percentiles of (map - ray) in voxels, the thin regions the report
// finds with min_wall one voxel under the wall, and the seconds taken.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "support/ray_thickness.h"
#include "support/test_meshes.h"
#include "support/test_parts.h"
#include "voxd/analysis/analysis.h"
#include "voxd/analysis/wall_thickness.h"
#include "voxd/voxelize/voxelize.h"

namespace {

using namespace voxd;

struct Part {
  std::string name;
  double wall;
  Mesh mesh;
};

// A cup about z: outer radius R, inner r, height H, floor f thick.
Mesh cup(double R, double r, double H, double f, int segments) {
  return test::make_lathe({{0, 0}, {R, 0}, {R, H}, {r, H}, {r, f}, {0, f}}, segments);
}

}  // namespace

int main(int argc, char** argv) {
  const double h = argc > 1 ? std::atof(argv[1]) : 0.05;
  const std::size_t points = argc > 2 ? static_cast<std::size_t>(std::atol(argv[2])) : 2000;
  std::vector<Part> parts = {
      {"tube R 6 / r 4.5, axis z", 1.5, test::make_tube(6, 4.5, 0, 6, 192)},
      {"tube R 10 / r 8, axis z", 2.0, test::make_tube(10, 8, 0, 6, 256)},
      {"tube R 5 / r 3.8, turned 30/20", 1.2, test::rotated(test::make_tube(5, 3.8, 0, 6, 160), 30, 20)},
      {"shell R 6 / r 4.8, turned 30/20", 1.2,
       test::rotated(test::concat({test::make_icosphere({0, 0, 0}, 6, 5), test::flipped(test::make_icosphere({0, 0, 0}, 4.8, 5))}),
                     30, 20)},
      {"cup R 8 / r 6.5, floor 2, turned 30/20", 1.5, test::rotated(cup(8, 6.5, 8, 2, 192), 30, 20)},
  };
  std::printf("voxel %.3g, %zu points a part\n", h, points);
  std::printf("| part | wall | ray min / mean | map min / mean | within ±1 voxel | ±1.5 | p1 / p50 / p99 of map - ray (voxels) | thin regions at wall - 1 voxel | seconds |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|\n");
  for (const Part& p : parts) {
    GridRequest request;
    request.kind = GridRequest::Kind::voxel_size;
    request.voxel_size = h;
    request.padding = 2;
    const BitVolume solid = voxelize_parity(p.mesh, resolve_grid(request, bounds(p.mesh)), 0, 0, nullptr);
    const auto t0 = std::chrono::steady_clock::now();
    const DenseVolume<float> map = wall_thickness(solid, 0);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const test::WallAgreement w = test::compare_with_rays(p.mesh, solid, map, points);
    AnalysisOptions options;
    options.skin = false;
    options.min_wall_voxels = p.wall / h - 1.0;
    options.thickness_map = &map;
    const AnalysisReport report = analyze_volume(solid, options);
    std::printf("| %s | %.3f | %.3f / %.3f | %.3f / %.3f | %.1f%% | %.1f%% | %.2f / %.2f / %.2f | %zu | %.1f |\n",
                p.name.c_str(), p.wall, w.ray_min, w.ray_mean, w.min, w.mean, 100 * w.within_1, 100 * w.within_1_5, w.p01,
                w.p50, w.p99, report.thickness->thin_regions.size(), seconds);
    std::fflush(stdout);
  }
}
