#pragma once
// Real meshes from Debian's assimp-testmodels package (the test corpus of the
// Open Asset Import Library, installed by scripts/install-deps.sh under
// /usr/share/assimp/models): binary and ASCII STL from several exporters, OBJ
// and PLY with odd encodings, open and broken files. The tests take their
// scanned, open and foreign files from there.
#include <filesystem>
#include <stdexcept>
#include <string>

namespace voxd::test {

inline const std::string kAssimpModels = "/usr/share/assimp/models";

// The path of a file of the corpus, e.g. "STL/Wuson.stl"; throws, naming the
// package, when it is not installed.
inline std::string assimp_model(const std::string& relative) {
  const std::string path = kAssimpModels + "/" + relative;
  if (!std::filesystem::exists(path))
    throw std::runtime_error(path + " is missing: install Debian's assimp-testmodels (scripts/install-deps.sh does)");
  return path;
}

}  // namespace voxd::test
