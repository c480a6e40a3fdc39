// Writes the benchmark mesh as a binary STL, for whole-CLI benchmarks:
//   write_bench_mesh OUT.stl                 the 1.1M-triangle torus
//   write_bench_mesh OUT.stl --small         its 10,000-triangle version
//   write_bench_mesh OUT.stl --triangles N   70000, 1100000 or 4400000
//                                            (cost against the triangle count)
#include <cstdio>
#include <string>

#include "bench_mesh.h"

int main(int argc, char** argv) {
  const std::string option = argc >= 3 ? argv[2] : "";
  voxd::Mesh mesh;
  if (argc == 2) {
    mesh = voxd::bench::make_benchmark_mesh();
  } else if (argc == 3 && option == "--small") {
    mesh = voxd::bench::make_small_benchmark_mesh();
  } else if (argc == 4 && option == "--triangles") {
    const std::string n = argv[3];
    if (n == "70000") mesh = voxd::bench::make_benchmark_torus(250, 140);
    else if (n == "1100000") mesh = voxd::bench::make_benchmark_mesh();
    else if (n == "4400000") mesh = voxd::bench::make_benchmark_torus(2000, 1100);
  }
  if (mesh.triangles.empty()) {
    std::fprintf(stderr, "usage: write_bench_mesh OUT.stl [--small | --triangles 70000|1100000|4400000]\n");
    return 2;
  }
  voxd::test::write_file(argv[1], voxd::test::to_binary_stl(mesh));
  return 0;
}
