// Wall thickness against the mesh's own ray thickness (tests/support/
// ray_thickness.h) on generated curved parts with exact walls: the table
// of issue #35 on the parts of tests/support/wall_parts.h, for measuring
// the analysis before and after a change.
//   build/bench/wall_accuracy [voxel_size=0.05] [points=2000]
// Prints, per part: the wall, the ray thickness's min/mean, the map's
// min/mean at the same surface points (2 voxels or more from sharp edges),
// the share of points within ±1 and ±1.5 voxels of the ray, the 1st, 50th
// and 99th percentiles of (map - ray) in voxels, the thin regions the report
// finds with min_wall one voxel under the wall, the seconds taken, and the
// thickness on the part's own vertices against the ray at each (those 2
// voxels or more from a sharp edge whose ray crosses a wall).
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "support/ray_thickness.h"
#include "support/test_meshes.h"
#include "support/wall_parts.h"
#include "voxd/analysis/analysis.h"
#include "voxd/analysis/surface_thickness.h"
#include "voxd/analysis/wall_thickness.h"
#include "voxd/mesh_report.h"
#include "voxd/voxelize/voxelize.h"

using namespace voxd;

int main(int argc, char** argv) {
  const double h = argc > 1 ? std::atof(argv[1]) : 0.05;
  const std::size_t points = argc > 2 ? static_cast<std::size_t>(std::atol(argv[2])) : 2000;
  const std::vector<test::WallPart> parts = test::curved_wall_parts();
  std::printf("voxel %.3g, %zu points a part\n", h, points);
  std::printf("| part | wall | ray min / mean | map min / mean | within ±1 voxel | ±1.5 | p1 / p50 / p99 of map - ray (voxels) | thin regions at wall - 1 voxel | seconds | vertices compared, within ±1 voxel |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
  for (const test::WallPart& p : parts) {
    const BitVolume solid = test::solid_of(p.mesh, h);
    const auto t0 = std::chrono::steady_clock::now();
    const DenseVolume<float> map = wall_thickness(solid, 0);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const test::WallAgreement w = test::compare_with_rays(p.mesh, solid, map, points);
    AnalysisOptions options;
    options.skin = false;
    options.min_wall_voxels = p.wall / h - 1.0;
    options.thickness_map = &map;
    const AnalysisReport report = analyze_volume(solid, options);
    // The thickness on the part's own (welded) vertices, against the ray at each.
    const Mesh welded = weld_vertices(p.mesh);
    const test::VertexAgreement on_part =
        test::compare_vertices_with_rays(welded, surface_thickness(welded, map).thickness, h);
    std::printf("| %s | %.3f | %.3f / %.3f | %.3f / %.3f | %.1f%% | %.1f%% | %.2f / %.2f / %.2f | %zu | %.1f | %zu, %.1f%% |\n",
                p.name.c_str(), p.wall, w.ray_min, w.ray_mean, w.min, w.mean, 100 * w.within_1, 100 * w.within_1_5, w.p01,
                w.p50, w.p99, report.thickness->thin_regions.size(), seconds, on_part.vertices, 100 * on_part.within_1);
    std::fflush(stdout);
  }
}
