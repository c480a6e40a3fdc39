#include "voxd/encode/slab_writer.h"

#include <stdexcept>
#include <variant>

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
  // The rest (vox, png-stack, a mode's mesh) need the whole volume; so does
  // a new format until its writer here says otherwise.
  return std::string(to_string(format)) + " does not stream slab by slab; write rle, raw or nrrd, or voxelize in memory";
}

namespace {

// What every slab writer keeps: the format, where the bytes go, which layer
// comes next.
struct SlabStream {
  SlabStream(const Grid& g, VolumeFormat f, const EncodeOptions& o, ByteSink& s, const char* w)
      : grid(g), format(f), options(o), sink(&s), writer(w) {}
  Grid grid;
  VolumeFormat format;
  EncodeOptions options;
  ByteSink* sink;
  const char* writer;            // for messages
  std::optional<GzipSink> gzip;  // nrrd with gzip encoding
  std::int64_t next_layer = 0;
  bool finished = false;

  // Where the voxels go: the gzip stream of a compressed NRRD, else the sink.
  ByteSink& data() { return gzip ? static_cast<ByteSink&>(*gzip) : *sink; }

  void nrrd_header(const char* type) {
    const std::string header = encode::nrrd_header(grid, type, options.content, options.nrrd_encoding);
    sink->write(header.data(), header.size());
    if (options.nrrd_encoding == NrrdEncoding::gzip) gzip.emplace(*sink);
  }
  void check(std::int64_t k0, const Grid& slab) const {
    if (finished || k0 != next_layer || slab.dims.x != grid.dims.x || slab.dims.y != grid.dims.y ||
        k0 + slab.dims.z > grid.dims.z)
      throw std::logic_error(std::string(writer) + ": slab of layers " + std::to_string(k0) + ".. out of order or off the grid");
  }
  // False when already finished; throws when layers are missing.
  bool begin_finish() const {
    if (finished) return false;
    if (next_layer != grid.dims.z)
      throw std::logic_error(std::string(writer) + ": finished after " + std::to_string(next_layer) + " of " +
                             std::to_string(grid.dims.z) + " layers");
    return true;
  }
};

}  // namespace

struct BitSlabWriter::State : SlabStream {
  using SlabStream::SlabStream;
  encode::BitPacker packer;  // raw bits
};

BitSlabWriter::BitSlabWriter(const Grid& grid, VolumeFormat format, const EncodeOptions& options, ByteSink& sink)
    : state_(std::make_unique<State>(grid, format, options, sink, "BitSlabWriter")) {
  if (auto refusal = streaming_refusal(format)) throw Error(ErrorCode::invalid_argument, *refusal);
  encode::require_voxels(grid, "streamed writer");
  switch (format) {
    case VolumeFormat::rle: encode::write_rle_bit_header(grid, sink); break;
    case VolumeFormat::nrrd: state_->nrrd_header("uchar"); break;
    default: break;  // raw has no header
  }
}

BitSlabWriter::~BitSlabWriter() = default;

void BitSlabWriter::write(std::int64_t k0, const BitVolume& slab) {
  State& s = *state_;
  s.check(k0, slab.grid());
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

void BitSlabWriter::write(std::int64_t k0, const RunSlab& slab) {
  State& s = *state_;
  if (s.format != VolumeFormat::rle) {
    write(k0, slab.to_bits());
    return;
  }
  s.check(k0, slab.grid());
  encode::write_rle_bit_layers(slab, k0, *s.sink);
  s.next_layer = k0 + slab.grid().dims.z;
}

RunSlabPreparer BitSlabWriter::preparer() const {
  if (state_->format != VolumeFormat::rle) return {};
  return prepare_rle_layer_blocks;
}

void BitSlabWriter::finish() {
  State& s = *state_;
  if (!s.begin_finish()) return;
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

void write_rle_head(const Grid& grid, ByteSink& sink) {
  encode::require_voxels(grid, "RLE writer");
  encode::write_rle_bit_header(grid, sink);
}

void write_rle_layer_blocks(std::int64_t k0, const BitVolume& slab, ByteSink& sink) {
  encode::write_rle_bit_layers(slab, k0, sink);
}

void write_rle_layer_blocks(std::int64_t k0, const RunSlab& slab, ByteSink& sink) {
  encode::write_rle_bit_layers(slab, k0, sink);
}

void prepare_rle_layer_blocks(std::int64_t k0, RunSlab& slab) {
  encode::encode_rle_bit_layers(slab, k0, slab.prepared().bytes);
  slab.prepared().k0 = k0;
}

void write_rle_tail(const Grid& grid, ByteSink& sink) { encode::write_rle_end(grid.dims.z, sink); }

std::optional<std::string> streaming_refusal(const ValueVolume& type, VolumeFormat format, const EncodeOptions& options) {
  if (auto refusal = format_refusal(type, format, options)) return refusal;
  if (format != VolumeFormat::rle && format != VolumeFormat::raw && format != VolumeFormat::nrrd)
    return std::string(to_string(format)) + " does not stream slab by slab; write rle, raw or nrrd, or run in memory";
  if (options.quantize != Quantize::none)
    return "quantized RLE does not stream slab by slab: its levels span the whole volume's range; write f32 rle, "
           "raw or nrrd, or run in memory";
  return std::nullopt;
}

struct ValueSlabWriter::State : SlabStream {
  State(const Grid& g, const ValueVolume& t, VolumeFormat f, const EncodeOptions& o, ByteSink& s)
      : SlabStream(g, f, o, s, "ValueSlabWriter"), type_index(t.index()) {}
  std::size_t type_index;
};

ValueSlabWriter::ValueSlabWriter(const Grid& grid, const ValueVolume& type, VolumeFormat format,
                                 const EncodeOptions& options, ByteSink& sink)
    : state_(std::make_unique<State>(grid, type, format, options, sink)) {
  if (auto refusal = streaming_refusal(type, format, options)) throw Error(ErrorCode::invalid_argument, *refusal);
  encode::require_voxels(grid, "streamed writer");
  switch (format) {
    case VolumeFormat::rle: encode::write_rle_value_header(type, grid, sink); break;
    case VolumeFormat::nrrd:
      state_->nrrd_header(std::holds_alternative<DenseVolume<float>>(type) ? "float" : "uchar");
      break;
    default: break;  // raw has no header
  }
}

ValueSlabWriter::~ValueSlabWriter() = default;

void ValueSlabWriter::write(std::int64_t k0, const ValueVolume& slab) {
  State& s = *state_;
  s.check(k0, grid_of(slab));
  if (slab.index() != s.type_index)
    throw std::logic_error(std::string("ValueSlabWriter: a slab of ") + value_type_name(slab) + " values");
  switch (s.format) {
    case VolumeFormat::rle: encode::write_rle_value_layers(slab, k0, *s.sink); break;
    case VolumeFormat::raw: std::visit([&](const auto& v) { write_raw(v, *s.sink); }, slab); break;
    case VolumeFormat::nrrd: std::visit([&](const auto& v) { write_raw(v, s.data()); }, slab); break;
    default: break;
  }
  s.next_layer = k0 + grid_of(slab).dims.z;
}

void ValueSlabWriter::finish() {
  State& s = *state_;
  if (!s.begin_finish()) return;
  if (s.format == VolumeFormat::rle) encode::write_rle_end(s.grid.dims.z, *s.sink);
  if (s.gzip) s.gzip->finish();
  s.finished = true;
}

}  // namespace voxd
