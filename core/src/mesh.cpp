#include "voxd/mesh.h"

#include <sys/mman.h>

#include <algorithm>
#include <cstdlib>
#include <limits>

#include "voxd/parallel.h"

namespace voxd {
namespace {

// Below this a heap block is cheaper than a mapping (a system call each way).
constexpr std::size_t kMappedMeshBytes = std::size_t{4} << 20;

}  // namespace

void* allocate_mesh_memory(std::size_t bytes) {
  if (bytes < kMappedMeshBytes) {
    void* p = std::malloc(std::max<std::size_t>(bytes, 1));
    if (!p) throw std::bad_alloc();
    return p;
  }
  void* p = ::mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (p == MAP_FAILED) throw std::bad_alloc();
  ::madvise(p, bytes, MADV_HUGEPAGE);  // a hint: refused where huge pages are off
  return p;
}

void free_mesh_memory(void* p, std::size_t bytes) noexcept {
  if (!p) return;
  if (bytes < kMappedMeshBytes)
    std::free(p);
  else
    ::munmap(p, bytes);
}

Aabb bounds(const Mesh& mesh) {
  if (mesh.triangles.empty()) return {};
  // Only vertices referenced by triangles count: decoders may keep unused
  // ones. Floats compared as floats: widening to double keeps the order, so
  // the box is the same, and a few threads share the millions of corners of
  // a large upload.
  constexpr float inf = std::numeric_limits<float>::infinity();
  const auto n = static_cast<std::int64_t>(mesh.triangles.size());
  constexpr std::int64_t kGrain = 1 << 18;
  std::vector<glm::vec3> lo(static_cast<std::size_t>((n + kGrain - 1) / kGrain), glm::vec3(inf)),
      hi(lo.size(), glm::vec3(-inf));
  parallel_for(0, n, kGrain, 0, [&](std::int64_t b, std::int64_t e) {
    glm::vec3 l(inf), h(-inf);
    for (std::int64_t t = b; t < e; ++t)
      for (std::uint32_t v : mesh.triangles[static_cast<std::size_t>(t)]) {
        const glm::vec3& p = mesh.vertices[v];
        for (int a = 0; a < 3; ++a) {
          l[a] = std::min(l[a], p[a]);
          h[a] = std::max(h[a], p[a]);
        }
      }
    lo[static_cast<std::size_t>(b / kGrain)] = l;
    hi[static_cast<std::size_t>(b / kGrain)] = h;
  });
  glm::vec3 l(inf), h(-inf);
  for (std::size_t i = 0; i < lo.size(); ++i)
    for (int a = 0; a < 3; ++a) {
      l[a] = std::min(l[a], lo[i][a]);
      h[a] = std::max(h[a], hi[i][a]);
    }
  return {glm::dvec3(l), glm::dvec3(h)};
}

}  // namespace voxd
