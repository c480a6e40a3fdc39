#include "voxd/encode/slab_writer.h"

#include <stdexcept>

#include "encode/bit_packer.h"
#include "encode/rle_stream.h"
#include "encode/nrrd_header.h"
#include "encode/volume_checks.h"
#include "voxd/error.h"

namespace voxd {

std::optional<std::string> streaming_refusal(VolumeFormat format) {
  switch (format) {
    case VolumeFormat::rle:
    case VolumeFormat::raw:
    case VolumeFormat::nrrd: return std::nullopt;
    case VolumeFormat::binvox:
      return "binvox does not stream slab by slab: its outer axis is x, so every x-slab needs every z layer; "
             "write rle, raw or nrrd, or voxelize in memory";
    default: break;
  }
  return std::string(to_string(format)) + " is not a format of bits";
}

struct BitSlabWriter::State {
  State(const Grid& g, VolumeFormat f, const EncodeOptions& o, ByteSink& s) : grid(g), format(f), options(o), sink(&s) {}
  Grid grid;
  VolumeFormat format;
  EncodeOptions options;
  ByteSink* sink;
  std::optional<GzipSink> gzip;  // nrrd with gzip encoding
  encode::BitPacker packer;      // raw bits
  std::int64_t next_layer = 0;
  bool finished = false;

  // Where the voxels go: the gzip stream of a compressed NRRD, else the sink.
  ByteSink& data() { return gzip ? static_cast<ByteSink&>(*gzip) : *sink; }
};

BitSlabWriter::BitSlabWriter(const Grid& grid, VolumeFormat format, const EncodeOptions& options, ByteSink& sink)
    : state_(std::make_unique<State>(grid, format, options, sink)) {
  if (auto refusal = streaming_refusal(format)) throw Error(ErrorCode::invalid_argument, *refusal);
  encode::require_voxels(grid, "streamed writer");
  switch (format) {
    case VolumeFormat::rle: encode::write_rle_bit_header(grid, sink); break;
    case VolumeFormat::nrrd: {
      const std::string header = encode::nrrd_header(grid, "uchar", options.content, options.nrrd_encoding);
      sink.write(header.data(), header.size());
      if (options.nrrd_encoding == NrrdEncoding::gzip) state_->gzip.emplace(sink);
      break;
    }
    default: break;  // raw has no header
  }
}

BitSlabWriter::~BitSlabWriter() = default;

void BitSlabWriter::write(std::int64_t k0, const BitVolume& slab) {
  State& s = *state_;
  if (s.finished || k0 != s.next_layer || slab.grid().dims.x != s.grid.dims.x || slab.grid().dims.y != s.grid.dims.y ||
      k0 + slab.grid().dims.z > s.grid.dims.z)
    throw std::logic_error("BitSlabWriter: slab of layers " + std::to_string(k0) + ".. out of order or off the grid");
  switch (s.format) {
    case VolumeFormat::rle: encode::write_rle_bit_layers(slab, k0, *s.sink); break;
    case VolumeFormat::raw:
      if (s.options.raw_packing == RawPacking::bits)
        encode::pack_raw_bits(slab, s.packer, *s.sink);
      else
        encode::write_raw_bytes(slab, *s.sink);
      break;
    case VolumeFormat::nrrd: encode::write_raw_bytes(slab, s.data()); break;
    default: break;
  }
  s.next_layer = k0 + slab.grid().dims.z;
}

void BitSlabWriter::finish() {
  State& s = *state_;
  if (s.finished) return;
  if (s.next_layer != s.grid.dims.z)
    throw std::logic_error("BitSlabWriter: finished after " + std::to_string(s.next_layer) + " of " +
                           std::to_string(s.grid.dims.z) + " layers");
  switch (s.format) {
    case VolumeFormat::rle: encode::write_rle_end(s.grid.dims.z, *s.sink); break;
    case VolumeFormat::raw:
      if (s.options.raw_packing == RawPacking::bits) s.packer.flush(*s.sink, true);
      break;
    case VolumeFormat::nrrd:
      if (s.gzip) s.gzip->finish();
      break;
    default: break;
  }
  s.finished = true;
}

}  // namespace voxd
