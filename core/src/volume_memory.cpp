#include "voxd/volume_memory.h"

#include <sys/mman.h>

#include <cstdlib>

namespace voxd {
namespace {

constexpr std::size_t kHeapMaxBytes = std::size_t{1} << 20;
constexpr std::size_t kHugePageMinBytes = std::size_t{8} << 20;

}  // namespace

void* allocate_volume_memory(std::size_t bytes, bool zeroed) {
  if (bytes < kHeapMaxBytes) {
    void* h = zeroed ? std::calloc(bytes ? bytes : 1, 1) : std::malloc(bytes ? bytes : 1);
    if (!h) throw std::bad_alloc();
    return h;
  }
  void* p = ::mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
  if (p == MAP_FAILED) throw std::bad_alloc();
  // No-op where transparent huge pages are disabled.
  if (bytes >= kHugePageMinBytes) ::madvise(p, bytes, MADV_HUGEPAGE);
  return p;
}

void free_volume_memory(void* p, std::size_t bytes) noexcept {
  if (!p) return;
  if (bytes < kHeapMaxBytes)
    std::free(p);
  else
    ::munmap(p, bytes);
}

}  // namespace voxd
