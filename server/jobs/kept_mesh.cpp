#include "server/jobs/kept_mesh.h"

#include <cstring>
#include <stdexcept>

namespace voxd::server {
namespace {

constexpr char kMagic[8] = {'V', 'O', 'X', 'D', 'M', 'S', 'H', '1'};
constexpr std::size_t kHeader = sizeof kMagic + 2 * sizeof(std::uint64_t) + 9 * sizeof(double);

}  // namespace

std::string encode_kept_mesh(const Mesh& welded, const glm::dmat3& rotation) {
  const std::uint64_t v = welded.vertices.size(), t = welded.triangles.size();
  std::string out(kHeader + 12 * v + 12 * t, '\0');
  char* p = out.data();
  auto put = [&](const void* data, std::size_t n) {
    std::memcpy(p, data, n);
    p += n;
  };
  put(kMagic, sizeof kMagic);
  put(&v, sizeof v);
  put(&t, sizeof t);
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) put(&rotation[c][r], sizeof(double));
  put(welded.vertices.data(), 12 * v);
  put(welded.triangles.data(), 12 * t);
  return out;
}

KeptMesh decode_kept_mesh(const std::string& bytes) {
  if (bytes.size() < kHeader || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0)
    throw std::runtime_error("the job's kept mesh is not one");
  const char* p = bytes.data() + sizeof kMagic;
  auto get = [&](void* data, std::size_t n) {
    std::memcpy(data, p, n);
    p += n;
  };
  std::uint64_t v = 0, t = 0;
  get(&v, sizeof v);
  get(&t, sizeof t);
  if (v > bytes.size() / 12 || t > bytes.size() / 12 || bytes.size() != kHeader + 12 * v + 12 * t)
    throw std::runtime_error("the job's kept mesh is truncated");
  KeptMesh k;
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) get(&k.rotation[c][r], sizeof(double));
  k.mesh.vertices.resize(v);
  k.mesh.triangles.resize(t);
  get(k.mesh.vertices.data(), 12 * v);
  get(k.mesh.triangles.data(), 12 * t);
  for (const auto& tri : k.mesh.triangles)
    for (const std::uint32_t i : tri)
      if (i >= v) throw std::runtime_error("the job's kept mesh has a triangle past its vertices");
  return k;
}

std::uint64_t kept_mesh_bytes(std::uint64_t triangles) { return kHeader + 36 * triangles + 12 * triangles; }

}  // namespace voxd::server
