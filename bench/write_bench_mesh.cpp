// Writes the benchmark mesh as a binary STL, for whole-CLI benchmarks.
#include <cstdio>

#include "bench_mesh.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: write_bench_mesh OUT.stl\n");
    return 2;
  }
  voxd::test::write_file(argv[1], voxd::test::to_binary_stl(voxd::bench::make_benchmark_mesh()));
  return 0;
}
