#pragma once
// Slice-function options that exercise every field of each function (an
// oblique axis, a ramp with a hard edge and a translucent stop, several
// octaves, an uneven lookup), for the tests that compare two ways of
// colouring a solid.
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

}  // namespace voxd::test
