#pragma once
// Writes a bit volume that arrives slab by slab in z order (streamed
// voxelization), so neither the writer nor the voxelizer ever holds the
// whole grid. The bytes are exactly encode_volume()'s for the whole volume.
// Formats whose order is z-slab major stream: rle, raw (bytes and bits) and
// nrrd (raw and gzip). binvox does not: its outer axis is x (each x-slab
// needs every z layer), so it needs the whole volume.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "voxd/bit_volume.h"
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
  // After the last layer: the format's trailer. Throws std::logic_error if
  // layers are missing.
  void finish();

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace voxd
