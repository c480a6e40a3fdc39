#pragma once
// Signed distance field options and meshes for the tests that compare two
// ways of computing the field (the CPU's scatter against the GPU's bricks,
// or their host emulation).
#include <cstdint>
#include <string>
#include <vector>

#include "support/slice_cases.h"
#include "support/test_meshes.h"
#include "voxd/voxelize/sdf.h"

namespace voxd::test {

// Bands narrow and wide, model and voxel units, both signs, the full field.
inline std::vector<SdfOptions> sdf_cases() {
  std::vector<SdfOptions> cases(4);
  cases[1].band = 1.5;
  cases[1].model_units = false;
  cases[1].sign = SignConvention::inside_positive;
  cases[2].band = 5.25;
  cases[3].band = 2.0;
  cases[3].full = true;
  for (SdfOptions& o : cases) o.threads = 2;
  return cases;
}

inline std::string describe(const SdfOptions& o) {
  return "band " + std::to_string(o.band) + (o.model_units ? " model" : " voxels") + " " + to_string(o.sign) +
         (o.full ? " full" : "");
}

// A turned torus, an open sphere (every 7th triangle gone) and a tilted
// tube.
inline std::vector<Mesh> sdf_case_meshes() {
  const std::vector<Mesh> slice = slice_case_meshes();
  return {slice[0], punched(make_icosphere({0.05, -0.1, 0.0}, 0.9, 3), 7), slice[2]};
}

// `n` voxels along the mesh's longest extent, 3 voxels of padding (the
// band reaches past the mesh).
inline Grid sdf_case_grid(const Mesh& mesh, std::int64_t n) {
  GridRequest r;
  r.resolution = n;
  r.padding = 3;
  return resolve_grid(r, bounds(mesh));
}

}  // namespace voxd::test
