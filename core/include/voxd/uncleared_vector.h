#pragma once
// A std::vector whose resize() leaves the new elements as the memory held
// them, for values about to be written by several threads: std::vector
// would first clear them all on the calling thread (and fault in every new
// page there). The memory is std::allocator's (the heap, or the kernel's
// ordinary pages for large blocks), not a volume's huge pages
// (voxd/volume_memory.h): an image or a slab of runs is written once, in
// rows, and a radiograph's maps on huge pages were slower to fault in than
// on ordinary ones on the development VM (docs/benchmarks.md, 2026-11-29).
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <utility>
#include <vector>

#include "voxd/parallel.h"

namespace voxd {

template <class T>
struct UnclearedAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = UnclearedAllocator<U>;
  };
  UnclearedAllocator() = default;
  template <class U>
  UnclearedAllocator(const UnclearedAllocator<U>&) noexcept {}
  template <class U>
  void construct(U* p) noexcept {
    ::new (static_cast<void*>(p)) U;  // default-initialized: left as it is
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

template <class T>
using UnclearedVector = std::vector<T, UnclearedAllocator<T>>;

// `v` as `n` copies of `value`, written in pieces of 1 MiB on up to
// `threads` threads (0: every core), so each page is faulted in by the
// thread that writes it: for buffers that start as zeros (a radiograph's
// maps, a preview's normals) and are then written on every thread. A 2048^2
// radiograph's map is 16 pieces, enough for 16 threads.
template <class T>
void assign_on_every_thread(UnclearedVector<T>& v, std::size_t n, const T& value, int threads = 0) {
  v.resize(n);
  const auto piece = static_cast<std::int64_t>(std::max<std::size_t>(1, (std::size_t{1} << 20) / sizeof(T)));
  parallel_for(0, static_cast<std::int64_t>(n), piece, threads, [&](std::int64_t a, std::int64_t b) {
    std::fill(v.begin() + a, v.begin() + b, value);
  });
}

// Drops the pages wholly inside [data, data + bytes) (madvise
// MADV_DONTNEED, so they read as zeros if touched again), in pieces of 4
// MiB on up to `threads` threads (0: every core). Freeing a large block
// makes the kernel walk and free every page it faulted in, about 0.2 us a 4
// KiB page on the thread that frees: 4 ms for a full slab of runs (64 MiB,
// voxd/run_slab.h), after work that took every core. Dropped here, the
// pages are freed by every thread and the block's free finds none. So
// are blocks the allocator would otherwise give back all at once later,
// on whichever thread frees next to them (the heap trimmed at its top).
// Never throws (it is a hint; destructors call it): where threads cannot
// be started it does what it can on fewer.
void release_pages_on_every_thread(void* data, std::size_t bytes, int threads = 0) noexcept;

// Frees `v`'s memory (capacity and all), its pages first released on up to
// `threads` threads as above (1: on the calling thread, as a piece of work
// shared out by the caller).
template <class T, class Allocator>
void free_on_every_thread(std::vector<T, Allocator>& v, int threads = 0) noexcept {
  release_pages_on_every_thread(v.data(), v.capacity() * sizeof(T), threads);
  std::vector<T, Allocator>().swap(v);
}

}  // namespace voxd
