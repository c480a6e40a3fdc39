#pragma once
// Parallel production with in-order consumption, for encoders whose output is
// a sequence of independently producible pieces: the RLE stream's slab blocks,
// binvox's word columns.
#include <cstddef>
#include <cstdint>
#include <functional>

namespace voxd::encode {

// Calls produce(i, slot) for i in [0, count) on up to `threads` threads
// (0 = default_thread_count()) and consume(i, slot) for each i in increasing
// order, always on the calling thread, so a ByteSink never sees another
// thread. Piece i uses slot i % slots, which the caller owns (a buffer per
// slot): a thread waits before producing piece i until piece i - slots has
// been consumed. That bounds memory to `slots` pieces without the barrier of
// fixed batches, where every thread waits for the slowest (on a busy machine
// that costs more than the work). The first exception from produce or
// consume stops the pipeline and is rethrown.
void run_ordered_pipeline(std::int64_t count, int threads, std::size_t slots,
                          const std::function<void(std::int64_t, std::size_t)>& produce,
                          const std::function<void(std::int64_t, std::size_t)>& consume);

}  // namespace voxd::encode
