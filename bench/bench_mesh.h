#pragma once
// The benchmark mesh: a closed, tilted torus of 1.1 million triangles (about
// the size of a detailed scanned or CAD part), generated so every run and
// every machine measures the same input.
#include "support/test_meshes.h"
#include "voxd/grid.h"
#include "voxd/transform.h"

namespace voxd::bench {

// The same torus and tilt with nu x nv quads (2 nu nv triangles), for cost
// against the triangle count.
inline Mesh make_benchmark_torus(int nu, int nv) {
  Mesh m = test::make_torus({0, 0, 0}, 1.0, 0.45, nu, nv);
  rotate_mesh(m, rotation_from_axis_angle({1.0, 0.7, 0.2}, 37.0));
  return m;
}

inline Mesh make_benchmark_mesh() { return make_benchmark_torus(1000, 550); }

// The service benchmark's small job: the same shape with 10,000 triangles,
// the size of a simple part a CAD plugin sends for a quick answer.
inline Mesh make_small_benchmark_mesh() { return make_benchmark_torus(100, 50); }

// The benchmark mesh, built once per process (it takes a second).
inline const Mesh& benchmark_mesh() {
  static const Mesh m = make_benchmark_mesh();
  return m;
}

// The grid `resolution` voxels along the benchmark mesh's longest extent,
// with `padding` empty voxels around it.
inline Grid benchmark_grid(std::int64_t resolution, std::int64_t padding = 1) {
  GridRequest r;
  r.resolution = resolution;
  r.padding = padding;
  return resolve_grid(r, bounds(benchmark_mesh()));
}

}  // namespace voxd::bench
