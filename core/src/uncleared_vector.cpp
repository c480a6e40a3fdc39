#include "voxd/uncleared_vector.h"

#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>

namespace voxd {

void release_pages_on_every_thread(void* data, std::size_t bytes, int threads) noexcept {
  constexpr std::uintptr_t kPiece = std::uintptr_t{4} << 20;
  const int n = threads > 0 ? threads : default_thread_count();
  if (data == nullptr) return;
  static const auto page = static_cast<std::uintptr_t>(::sysconf(_SC_PAGESIZE));
  const auto at = reinterpret_cast<std::uintptr_t>(data);
  // Whole pages only: the block's first and last bytes may share a page
  // with the allocator's own bookkeeping.
  const std::uintptr_t first = (at + page - 1) / page * page;
  const std::uintptr_t last = (at + bytes) / page * page;
  if (last <= first) return;
  const auto pieces = static_cast<std::int64_t>((last - first + kPiece - 1) / kPiece);
  const auto release = [&](std::int64_t p0, std::int64_t p1) {
    for (std::int64_t p = p0; p < p1; ++p) {
      const std::uintptr_t from = first + static_cast<std::uintptr_t>(p) * kPiece;
      const std::uintptr_t to = std::min(last, from + kPiece);
      // A hint: where it fails, the free that follows returns the pages.
      ::madvise(reinterpret_cast<void*>(from), to - from, MADV_DONTNEED);
    }
  };
  try {
    parallel_for(0, pieces, 1, n, release);
  } catch (...) {
    // No threads to be had (parallel_for's pieces themselves cannot throw):
    // the free that follows gives the pages back.
  }
}

}  // namespace voxd
