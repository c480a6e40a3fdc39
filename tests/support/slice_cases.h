#pragma once
#include <cstdint>
#include <vector>

// Slice-function options that exercise every field of each function (an
// oblique axis, a ramp with a hard edge and a translucent stop, several
// octaves, an uneven lookup), for the tests that compare two ways of
// colouring a solid.
#include "support/test_meshes.h"
#include "voxd/grid.h"
#include "voxd/transform.h"
#include "voxd/voxelize/slice_functions.h"

namespace voxd::test {

inline constexpr SliceFunction kAllSliceFunctions[] = {
    SliceFunction::single_color, SliceFunction::color_ramp, SliceFunction::interpolated_colors,
    SliceFunction::checker,      SliceFunction::wood,       SliceFunction::marble,
    SliceFunction::rock,         SliceFunction::custom};

inline SliceOptions slice_case(SliceFunction f) {
  SliceOptions o;
  o.function = f;
  o.axis = {0.3, -0.5, 1.0};
  o.ramp = {{0.0, {10, 20, 30, 255}}, {0.4, {250, 0, 90, 200}}, {0.4, {0, 255, 0, 255}}, {1.0, {30, 40, 250, 255}}};
  o.checker_size = 0.37;
  o.noise_scale = 0.4;
  o.period = 0.6;
  o.octaves = 3;
  o.seed = 7;
  o.lookup_dims = {2, 1, 3};
  o.lookup_colors = {{255, 0, 0, 255}, {0, 255, 0, 255}, {0, 0, 255, 255},
                     {255, 255, 0, 255}, {0, 255, 255, 255}, {255, 0, 255, 128}};
  return o;
}

// A grid of `n` voxels along the mesh's longest extent, 1 voxel of padding.
inline Grid slice_case_grid(const Mesh& mesh, std::int64_t n) {
  GridRequest r;
  r.resolution = n;
  r.padding = 1;
  return resolve_grid(r, bounds(mesh));
}

// Three solids to colour: a turned torus, a sphere and a tilted tube.
inline std::vector<Mesh> slice_case_meshes() {
  Mesh torus = make_torus({0.1, -0.2, 0.05}, 1.0, 0.4, 48, 24);
  rotate_mesh(torus, rotation_from_axis_angle({1.0, 0.3, 0.2}, 33.0));
  return {torus, make_icosphere({0.3, 0.1, -0.2}, 1.1, 3), rotated(make_tube(1.0, 0.6, -0.8, 0.9, 40), 20.0, 35.0)};
}

}  // namespace voxd::test
