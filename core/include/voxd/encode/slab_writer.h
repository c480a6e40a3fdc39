#pragma once
// Writes a bit volume that arrives slab by slab in z order (streamed
// voxelization), so neither the writer nor the voxelizer ever holds the
// whole grid. The bytes are exactly encode_volume()'s for the whole volume.
// Formats whose order is z-slab major stream: rle, raw (bytes and bits) and
// nrrd (raw and gzip). binvox does not: its outer axis is x (each x-slab
// needs every z layer), so it needs the whole volume.
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "voxd/bit_volume.h"
#include "voxd/run_slab.h"
#include "voxd/byte_sink.h"
#include "voxd/encode/volume_format.h"

namespace voxd {

// Whether `format` streams slab by slab (and why not, when it does not).
std::optional<std::string> streaming_refusal(VolumeFormat format);

class BitSlabWriter {
 public:
  // Writes the header. Throws Error(invalid_argument) for a format that does
  // not stream (streaming_refusal) or an empty grid.
  BitSlabWriter(const Grid& grid, VolumeFormat format, const EncodeOptions& options, ByteSink& sink);
  ~BitSlabWriter();
  BitSlabWriter(const BitSlabWriter&) = delete;
  BitSlabWriter& operator=(const BitSlabWriter&) = delete;

  // The grid's z layers [k0, k0 + slab.grid().dims.z), right after the
  // previous slab's. Throws std::logic_error out of order.
  void write(std::int64_t k0, const BitVolume& slab);
  // The same from runs (voxd/voxelize/runs.h): an RLE straight from them,
  // other formats through the slab's bits.
  void write(std::int64_t k0, const RunSlab& slab);
  // What the threads that make the slabs of runs can do for write(): encode
  // each slab's RLE blocks as it is made (prepare_rle_layer_blocks), so that
  // write() only copies them and the one thread writing in order does not
  // bound how many make them. Empty for the formats written from bits.
  RunSlabPreparer preparer() const;
  // After the last layer: the format's trailer. Throws std::logic_error if
  // layers are missing.
  void finish();

 private:
  struct State;
  std::unique_ptr<State> state_;
};

// A bit volume's RLE in parts made apart (a huge job's slab tasks on many
// workers, each with its own range of layers): the head, then each part's
// layer blocks in z order, then the tail are byte for byte BitSlabWriter's
// RLE of the whole grid, since that stream is one block per layer
// (proto-schemas/rle-format.md).
void write_rle_head(const Grid& grid, ByteSink& sink);
// The blocks of z layers [k0, k0 + slab.grid().dims.z).
void write_rle_layer_blocks(std::int64_t k0, const BitVolume& slab, ByteSink& sink);
void write_rle_layer_blocks(std::int64_t k0, const RunSlab& slab, ByteSink& sink);
// Encodes the slab's layer blocks (z layers from k0) into slab.prepared(),
// for write_rle_layer_blocks and BitSlabWriter::write to copy: a
// RunSlabPreparer (voxelize_runs), run on the thread that made the slab.
void prepare_rle_layer_blocks(std::int64_t k0, RunSlab& slab);
void write_rle_tail(const Grid& grid, ByteSink& sink);

// The same for a volume of values (coverage bytes or fractions; u8, f32 or
// rgba8) that arrives slab by slab: exactly encode_volume()'s bytes, in the
// formats of z-slab order that hold the type (rle, raw, nrrd), the quantized
// RLE apart (its levels span the whole volume's range, known only at the end).
// nullopt when `format` with `options` streams values of `type`'s type.
std::optional<std::string> streaming_refusal(const ValueVolume& type, VolumeFormat format, const EncodeOptions& options);

// Receives z layers [k0, k0 + n) of a volume of values, as BitSlabConsumer
// does bits (voxd/bit_slabs.h).
using ValueSlabConsumer = std::function<void(std::int64_t k0, const ValueVolume& slab)>;

class ValueSlabWriter {
 public:
  // Writes the header. `type` is any volume of the values' type (an empty
  // one will do). Throws Error(invalid_argument) for a format that does not
  // stream them (streaming_refusal) or an empty grid.
  ValueSlabWriter(const Grid& grid, const ValueVolume& type, VolumeFormat format, const EncodeOptions& options,
                  ByteSink& sink);
  ~ValueSlabWriter();
  ValueSlabWriter(const ValueSlabWriter&) = delete;
  ValueSlabWriter& operator=(const ValueSlabWriter&) = delete;

  // As BitSlabWriter's; a slab of another type is a std::logic_error.
  void write(std::int64_t k0, const ValueVolume& slab);
  void finish();

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace voxd
