#pragma once
// Memory for voxel volumes. Large ones come straight from the OS on
// transparent huge pages where the kernel allows them (its "madvise" mode):
// writing a fresh 0.5 GB volume on 4 KiB pages is mostly page faults (1.8 s
// on the 2-core benchmark machine), on 2 MiB pages 0.06 s. Small ones, the
// service's many quick jobs, come from the heap: an mmap and munmap per
// volume costs system calls and cross-core TLB flushes. The last few large
// blocks given back (64 MiB to 1 GiB in all) are kept for the next volume of
// their size or smaller (a larger block returns its tail), which then skips
// the kernel's page faults and clearing (one asked zeroed gets the block's pages dropped, so it starts
// as fresh zero pages do); mapping any other new block returns them first. A host that
// would rather have every block returned at once (a plugin inside a CAD
// program sharing its memory) turns that off: set_keep_freed_volumes(false).
#include <cstddef>
#include <new>
#include <utility>
#include <vector>

namespace voxd {

// `bytes` of memory, zero-filled when `zeroed` (fresh OS pages are zero
// anyway; only small heap blocks are cleared). Throws std::bad_alloc.
void* allocate_volume_memory(std::size_t bytes, bool zeroed);
// Gives back what allocate_volume_memory(bytes, ...) returned.
void free_volume_memory(void* p, std::size_t bytes) noexcept;

// Whether large blocks given back are kept for the next volume of their size
// (on by default). Turning it off returns the blocks kept now.
void set_keep_freed_volumes(bool keep) noexcept;
bool keeps_freed_volumes() noexcept;

// How a VolumeAllocator's vector initializes the elements it creates
// without a value (resize, a count alone).
enum class VolumeInit {
  values,  // value-initialized (zeros), written as std::allocator does
  zeroed,  // asks allocate_volume_memory for zeroed memory and writes nothing
  none,    // writes nothing: the elements hold what the memory held
};

// An allocator over allocate_volume_memory, for the values of dense
// volumes (voxd/dense_volume.h). VolumeInit::zeroed makes a fresh volume of
// zeros cost no pass over it: its fresh pages are faulted in and cleared by
// whichever threads first write them, not by one thread filling the whole
// volume before the work starts. VolumeInit::none is for a volume about to
// be overwritten whole (read from a file). Either way the vector must not
// grow within its capacity after shrinking (the elements it would
// value-initialize there hold old values); dense volumes never do.
template <class T>
struct VolumeAllocator {
  using value_type = T;
  VolumeInit init = VolumeInit::values;
  VolumeAllocator() = default;
  explicit VolumeAllocator(VolumeInit how) noexcept : init(how) {}
  template <class U>
  VolumeAllocator(const VolumeAllocator<U>& other) noexcept : init(other.init) {}
  T* allocate(std::size_t n) {
    if (n > static_cast<std::size_t>(-1) / sizeof(T)) throw std::bad_alloc();
    return static_cast<T*>(allocate_volume_memory(n * sizeof(T), init == VolumeInit::zeroed));
  }
  void deallocate(T* p, std::size_t n) noexcept { free_volume_memory(p, n * sizeof(T)); }
  template <class U>
  void construct(U* p) {
    if (init == VolumeInit::values)
      ::new (static_cast<void*>(p)) U();
    else
      ::new (static_cast<void*>(p)) U;  // default-initialized: the memory stays as it is
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
  // A copy writes every element anyway.
  VolumeAllocator select_on_container_copy_construction() const noexcept { return {}; }
};
template <class T, class U>
bool operator==(const VolumeAllocator<T>&, const VolumeAllocator<U>&) noexcept {
  return true;  // any of them frees what any other allocated
}

template <class T>
using VolumeVector = std::vector<T, VolumeAllocator<T>>;

}  // namespace voxd
