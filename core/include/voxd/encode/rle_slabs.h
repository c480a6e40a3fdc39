#pragma once
// A stored bit RLE stream (proto-schemas/rle-format.md) replayed z-slab by
// z-slab, so a result larger than memory is re-encoded and analysed without
// ever being loaded whole: memory is one slab of `slab_layers` layers.
#include <cstdint>
#include <span>

#include "voxd/bit_slabs.h"
#include "voxd/byte_source.h"
#include "voxd/encode/slab_writer.h"
#include "voxd/encode/volume_format.h"
#include "voxd/grid.h"
#include "voxd/run_slab.h"

namespace voxd {

// The grid of a bit RLE stream, from its header. Throws like read_rle_bits.
Grid read_rle_bit_grid(std::span<const std::uint8_t> data);
Grid read_rle_bit_grid(ByteSource& source);

// Decodes the stream's layers into slabs of `slab_layers` layers (the last
// one shorter when nz is not a multiple), calling `consume` for each in z
// order, as the streamed voxelizer does. Each block is checked as it is
// reached: a malformed one throws Error(malformed_input / truncated_input)
// after the slabs before it were handed on, so a consumer that must not act
// on half a volume checks the stream first or stops on the throw. A consumer
// may throw to stop early. `limits` bounds one slab's memory (the header's
// dims are not trusted): Error(limit_exceeded) before anything is allocated.
void read_rle_bit_slabs(std::span<const std::uint8_t> data, std::int64_t slab_layers, const BitSlabConsumer& consume,
                        const ReadLimits& limits = {});
// The same from a source read front to back (a stored result fetched as it
// is read): memory is one slab and one layer's block, never the stream.
void read_rle_bit_slabs(ByteSource& source, std::int64_t slab_layers, const BitSlabConsumer& consume,
                        const ReadLimits& limits = {});

// The same stream's filled runs, row by row (RunSlab), never its bits: the
// streamed analyses that work on runs (mass properties, parts and voids)
// then cost the runs, not the voxels (an 8192^3 result is 136 MiB of runs
// and 64 GiB of bits). A slab holds up to `slab_layers` whole layers, fewer
// once it holds kRunSlabRuns runs, and never more than kRunSlabRuns rows;
// memory is one slab. Checked and thrown
// like read_rle_bit_slabs; `limits` bounds the runs one layer can need.
//
// On more than one of `threads` (0 = every core) the layers are decoded
// in batches, each layer apart on any thread, then joined into the slabs
// in order on the calling thread: the same slabs, the same consumer calls
// and the same error (the first bad block's) as on one thread. A batch of
// more than one layer holds at most kRunReaderBatchPayload bytes of payload
// and kRunReaderBatchRows rows (a larger layer is read alone, as on one
// thread); see run_reader_batch_bytes for what that costs.
inline constexpr std::size_t kRunSlabRuns = std::size_t{1} << 23;
inline constexpr std::size_t kRunReaderBatchPayload = std::size_t{4} << 20;
inline constexpr std::size_t kRunReaderBatchRows = std::size_t{1} << 20;
void read_rle_run_slabs(ByteSource& source, std::int64_t slab_layers, const RunSlabConsumer& consume,
                        const ReadLimits& limits = {}, int threads = 1);
void read_rle_run_slabs(std::span<const std::uint8_t> data, std::int64_t slab_layers, const RunSlabConsumer& consume,
                        const ReadLimits& limits = {}, int threads = 1);
// The most memory the parallel reader's batch holds beside the slab, read
// on `threads` threads (0 = every core): its payload, copied when the source
// is not in memory, and its layers' runs (a run takes at least two bytes of
// payload and 8 bytes decoded, a row start 4 bytes, a row may split a run).
std::uint64_t run_reader_batch_bytes(int threads);

// The same for a stream of values (u8, f32 or rgba8), each slab a
// ValueVolume of the stream's type (ValueSlabWriter's input).
void read_rle_value_slabs(std::span<const std::uint8_t> data, std::int64_t slab_layers, const ValueSlabConsumer& consume,
                          const ReadLimits& limits = {});
void read_rle_value_slabs(ByteSource& source, std::int64_t slab_layers, const ValueSlabConsumer& consume,
                          const ReadLimits& limits = {});

}  // namespace voxd
