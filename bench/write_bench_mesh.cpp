// Writes the benchmark mesh as a binary STL, for whole-CLI benchmarks.
#include <cstdio>
#include <string>

#include "bench_mesh.h"

int main(int argc, char** argv) {
  const bool small = argc == 3 && std::string(argv[2]) == "--small";
  if (argc != 2 && !small) {
    std::fprintf(stderr, "usage: write_bench_mesh OUT.stl [--small]\n");
    return 2;
  }
  const voxd::Mesh mesh = small ? voxd::bench::make_small_benchmark_mesh() : voxd::bench::make_benchmark_mesh();
  voxd::test::write_file(argv[1], voxd::test::to_binary_stl(mesh));
  return 0;
}
