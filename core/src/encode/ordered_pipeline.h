#pragma once
// Parallel encoding with in-order output, for encoders whose output is a
// sequence of independently encodable pieces (the RLE stream's slab blocks).
#include <cstdint>
#include <functional>

#include "encode/byte_buffer.h"

namespace voxd::encode {

// Calls encode(i, buffer) for i in [0, count) on up to `threads` threads
// (0 = default_thread_count()) and write(i, buffer) for each i in increasing
// order, always on the calling thread, so a ByteSink never sees another
// thread. At most `slots` encoded pieces exist at once: a thread waits before
// encoding piece i until piece i - slots has been written, which bounds memory
// without the barrier of fixed batches (where every thread waits for the
// slowest, which on a busy machine costs more than the encoding). The first
// exception from encode or write stops the pipeline and is rethrown.
void encode_in_order(std::int64_t count, int threads, std::int64_t slots,
                     const std::function<void(std::int64_t, ByteBuffer&)>& encode,
                     const std::function<void(std::int64_t, ByteBuffer&)>& write);

}  // namespace voxd::encode
