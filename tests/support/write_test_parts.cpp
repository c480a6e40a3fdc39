// Writes every part of test_parts.h as binary STL into a folder: the files
// the tests hand to the CLI, the service, the Python client and the fuzzers.
//   write_test_parts DIR
#include <filesystem>
#include <iostream>

#include "support/test_meshes.h"
#include "support/test_parts.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: write_test_parts DIR\n";
    return 2;
  }
  const std::filesystem::path dir = argv[1];
  std::filesystem::create_directories(dir);
  for (const voxd::test::Part& part : voxd::test::all_parts()) {
    voxd::test::write_file((dir / part.name).string(), voxd::test::to_binary_stl(part.mesh, "voxd test part " + part.name));
  }
  return 0;
}
