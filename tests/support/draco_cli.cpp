#include "support/draco_cli.h"

#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <unistd.h>

#include "support/test_meshes.h"

namespace voxd::test {

bool draco_encoder_available() { return ::access(kDracoEncoder, X_OK) == 0; }

std::vector<std::uint8_t> encode_with_draco_encoder(const Mesh& mesh, const std::string& flags) {
  std::string pattern = (std::filesystem::temp_directory_path() / "voxd-draco-XXXXXX").string();
  if (::mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("cannot create a temporary folder");
  const std::filesystem::path dir = pattern;
  const std::string obj = to_obj(mesh);
  write_file((dir / "mesh.obj").string(), {obj.begin(), obj.end()});
  const std::string command = std::string(kDracoEncoder) + " -i " + (dir / "mesh.obj").string() + " -o " +
                              (dir / "mesh.drc").string() + " " + flags + " > " + (dir / "log.txt").string() +
                              " 2>&1";
  const int status = std::system(command.c_str());
  std::vector<std::uint8_t> encoded;
  if (status == 0) encoded = read_file((dir / "mesh.drc").string());
  std::string log;
  if (status != 0) {
    const auto bytes = read_file((dir / "log.txt").string());
    log.assign(bytes.begin(), bytes.end());
  }
  std::filesystem::remove_all(dir);
  if (status != 0) throw std::runtime_error("'" + command + "' failed: " + log);
  return encoded;
}

}  // namespace voxd::test
