#pragma once
// Minimal fork-join parallel loop over an index range, split into contiguous
// chunks claimed dynamically, so uneven work (dense vs empty slabs) balances.
#include <cstdint>
#include <functional>

namespace voxd {

// Number of worker threads to use when a caller passes 0: hardware concurrency.
int default_thread_count();

// Calls body(chunk_begin, chunk_end) for consecutive chunks of [begin, end) of
// at most `grain` indices, on up to `threads` threads (0 = default). The first
// exception thrown by a body is rethrown on the calling thread after all
// threads stop claiming chunks.
void parallel_for(std::int64_t begin, std::int64_t end, std::int64_t grain, int threads,
                  const std::function<void(std::int64_t, std::int64_t)>& body);

}  // namespace voxd
