#include "voxd/volume_memory.h"

#include <sys/mman.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <vector>

namespace voxd {
namespace {

constexpr std::size_t kHeapMaxBytes = std::size_t{1} << 20;
constexpr std::size_t kHugePageMinBytes = std::size_t{8} << 20;

// Large blocks just given back, kept for the next volume of the same size
// or smaller: a service running one grid after another (and a benchmark's
// repeated runs) then skips the kernel's page faults and clearing, which on
// the 2-core benchmark VM cost about 1 s of CPU per GB. A larger block has
// its tail returned, and mapping any new block first returns the kept ones,
// so the process never holds kept memory while it grows.
class KeptBlocks {
 public:
  static constexpr std::size_t kMinBytes = std::size_t{64} << 20;
  static constexpr std::size_t kMaxBytes = std::size_t{1} << 30;
  static constexpr std::size_t kMaxBlocks = 4;

  void enable(bool on) noexcept {
    enabled_.store(on, std::memory_order_relaxed);
    if (on) return;
    std::lock_guard lock(mutex_);
    release_all();
  }
  bool enabled() const noexcept { return enabled_.load(std::memory_order_relaxed); }

  // A kept block of `bytes`, else the smallest larger one with its tail
  // unmapped: a report frees its 4-byte feature transform before it makes
  // its 2-byte peel depths, which then skip faulting in 200 MB at 512^3.
  void* take(std::size_t bytes) {
    std::lock_guard lock(mutex_);
    std::size_t best = blocks_.size();
    for (std::size_t b = 0; b < blocks_.size(); ++b) {
      if (blocks_[b].bytes == bytes) {
        best = b;
        break;
      }
      if (blocks_[b].bytes > bytes && (best == blocks_.size() || blocks_[b].bytes < blocks_[best].bytes)) best = b;
    }
    if (best < blocks_.size()) {
      const Block block = blocks_[best];
      kept_ -= block.bytes;
      blocks_.erase(blocks_.begin() + static_cast<std::ptrdiff_t>(best));
      const std::size_t used = page_rounded(bytes), mapped = page_rounded(block.bytes);
      if (used < mapped) ::munmap(static_cast<char*>(block.p) + used, mapped - used);
      return block.p;
    }
    // About to map new memory: give the kept blocks back first.
    release_all();
    return nullptr;
  }

  // True when kept (the caller must not unmap it).
  bool keep(void* p, std::size_t bytes) noexcept {
    if (bytes < kMinBytes || bytes > kMaxBytes || !enabled_.load(std::memory_order_relaxed)) return false;
    std::lock_guard lock(mutex_);
    if (blocks_.size() == kMaxBlocks || kept_ + bytes > kMaxBytes) return false;
    try {
      blocks_.push_back({p, bytes});
    } catch (...) {
      return false;
    }
    kept_ += bytes;
    return true;
  }

 private:
  struct Block {
    void* p;
    std::size_t bytes;
  };
  static std::size_t page_rounded(std::size_t bytes) noexcept {
    static const auto page = static_cast<std::size_t>(::sysconf(_SC_PAGESIZE));
    return (bytes + page - 1) / page * page;
  }
  void release_all() noexcept {  // caller holds mutex_
    for (const Block& block : blocks_) ::munmap(block.p, block.bytes);
    blocks_.clear();
    kept_ = 0;
  }
  std::atomic<bool> enabled_{true};
  std::mutex mutex_;
  std::vector<Block> blocks_;
  std::size_t kept_ = 0;
};

KeptBlocks& kept_blocks() {
  static KeptBlocks* blocks = new KeptBlocks;  // never destroyed: frees may come during exit
  return *blocks;
}

}  // namespace

void* allocate_volume_memory(std::size_t bytes, bool zeroed) {
  if (bytes < kHeapMaxBytes) {
    void* h = zeroed ? std::calloc(bytes ? bytes : 1, 1) : std::malloc(bytes ? bytes : 1);
    if (!h) throw std::bad_alloc();
    return h;
  }
  if (bytes >= KeptBlocks::kMinBytes) {
    if (void* kept = kept_blocks().take(bytes)) {
      // Reused pages hold the last volume. Asked zeroed, they are dropped
      // rather than cleared here: the kernel gives fresh zero pages to
      // whichever thread writes each first, as for a new mapping, instead of
      // one thread clearing (and faulting in) the whole block before the
      // work starts (0.2 s of a 512^3 report's wall thickness, serially).
      if (zeroed && ::madvise(kept, bytes, MADV_DONTNEED) != 0) std::memset(kept, 0, bytes);
      return kept;
    }
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
  else if (!kept_blocks().keep(p, bytes))
    ::munmap(p, bytes);
}

void set_keep_freed_volumes(bool keep) noexcept { kept_blocks().enable(keep); }
bool keeps_freed_volumes() noexcept { return kept_blocks().enabled(); }

}  // namespace voxd
