#pragma once
// Thin and thick regions of a thickness map (the report's is the wall
// thickness, voxd/analysis/wall_thickness.h; any map in voxels will do):
// the connected sets of filled voxels whose thickness is below (thin) or above
// (thick) a threshold, the places a design review has to look at.
//
// Connectivity is 26 (faces, edges and corners): a thin wall that steps
// diagonally through the grid, as a tilted wall does once voxelized, stays
// one region instead of breaking into many small ones.
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "voxd/dense_volume.h"

namespace voxd {

enum class ThicknessRegionKind {
  thin,   // filled voxels with 0 < thickness < threshold
  thick,  // filled voxels with thickness > threshold
};

struct ThicknessRegion {
  std::uint64_t voxel_count = 0;
  glm::i64vec3 bbox_min{0};  // voxel indices, inclusive
  glm::i64vec3 bbox_max{0};  // voxel indices, inclusive
  // Mean voxel index of the region's voxels. In model units its centre is
  // grid.origin + (centroid + 0.5) * grid.voxel_size.
  glm::dvec3 centroid{0.0};
  // The region's extreme thickness, in voxels: the minimum for a thin region,
  // the maximum for a thick one.
  float extreme_thickness = 0.0f;
  float mean_thickness = 0.0f;  // over the region's voxels, in voxels
};

// Regions of at least `min_voxels` voxels, most severe first: a thin region
// by its minimum ascending, a thick one by its maximum descending; ties by
// size (largest first), then by their first voxel (z, then y, then x): the
// same input always gives the same list.
//
// `probes` (voxel indices, as DenseVolume::index gives them), when given,
// are answered in `probe_regions`: for each, 1 + the index in the returned
// list of the region it lies in, or 0 for none (what a vertex on the part's
// surface reads, voxd/analysis/surface_thickness.h).
//
// `threads` 0 = all cores; the result does not depend on it. The mean
// thickness is the exact sum of the voxels' values (below 2^-41 voxels a
// value counts as 0, from 2^30 up as 2^30) over their count, rounded once.
std::vector<ThicknessRegion> find_thickness_regions(const DenseVolume<float>& thickness, ThicknessRegionKind kind,
                                                    float threshold_voxels, std::uint64_t min_voxels,
                                                    const std::vector<std::size_t>* probes = nullptr,
                                                    std::vector<std::uint32_t>* probe_regions = nullptr,
                                                    int threads = 0);

// One selection of the map: its kind and threshold, in voxels.
struct ThicknessRegionQuery {
  ThicknessRegionKind kind = ThicknessRegionKind::thin;
  float threshold_voxels = 0.0f;
};

// Each query's regions, exactly as find_thickness_regions finds them one at
// a time, from one pass over the map (the report asks four queries of a map
// of hundreds of megabytes).
std::vector<std::vector<ThicknessRegion>> find_thickness_regions(const DenseVolume<float>& thickness,
                                                                 const std::vector<ThicknessRegionQuery>& queries,
                                                                 std::uint64_t min_voxels, int threads = 0);

}  // namespace voxd
