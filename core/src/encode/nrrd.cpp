// NRRD (teem's Nearly Raw Raster Data, format 0004): a text header, a blank
// line, then the voxels x fastest as write_raw() lays them out, uncompressed
// or as one gzip stream. ParaView, 3D Slicer and ITK read it directly.
#include <string>

#include "encode/nrrd_header.h"
#include "encode/volume_checks.h"
#include "voxd/encode/number_text.h"
#include "voxd/encode/volume_format.h"

namespace voxd {
namespace encode {

std::string nrrd_header(const Grid& g, const char* type, std::string_view content, NrrdEncoding encoding) {
  const double h = g.voxel_size;
  // NRRD samples are node-centred: the space origin is the first voxel's
  // centre, and each axis steps one voxel size.
  std::string header = "NRRD0004\n# written by voxd\n";
  std::string text(content);
  for (char& c : text)
    if (c == '\n' || c == '\r') c = ' ';
  header += "content: " + text + "\n";
  header += std::string("type: ") + type + "\ndimension: 3\n";
  header += "space dimension: 3\n";
  header += "sizes: " + std::to_string(g.dims.x) + " " + std::to_string(g.dims.y) + " " + std::to_string(g.dims.z) + "\n";
  header += "space directions: (" + number_text(h) + ",0,0) (0," + number_text(h) + ",0) (0,0," + number_text(h) + ")\n";
  header += "space origin: (" + number_text(g.origin.x + 0.5 * h) + "," + number_text(g.origin.y + 0.5 * h) + "," +
            number_text(g.origin.z + 0.5 * h) + ")\n";
  header += "kinds: domain domain domain\ncenterings: cell cell cell\n";
  // Byte order only matters for multi-byte types; NRRD readers reject the
  // field's absence there and tolerate it everywhere.
  header += "endian: little\n";
  header += encoding == NrrdEncoding::gzip ? "encoding: gzip\n\n" : "encoding: raw\n\n";
  return header;
}

}  // namespace encode
namespace {

template <class WriteData>
void write_nrrd_with(const Grid& grid, const char* type, std::string_view content, NrrdEncoding encoding,
                     ByteSink& sink, const WriteData& write_data) {
  encode::require_voxels(grid, "NRRD writer");
  const std::string header = encode::nrrd_header(grid, type, content, encoding);
  sink.write(header.data(), header.size());
  if (encoding == NrrdEncoding::raw) return write_data(sink);
  GzipSink gzip(sink);
  write_data(gzip);
  gzip.finish();
}

}  // namespace

void write_nrrd(const BitVolume& volume, std::string_view content, ByteSink& sink, NrrdEncoding encoding) {
  write_nrrd_with(volume.grid(), "uchar", content, encoding, sink,
                  [&](ByteSink& out) { write_raw(volume, RawPacking::bytes, out); });
}

void write_nrrd(const DenseVolume<std::uint8_t>& volume, std::string_view content, ByteSink& sink,
                NrrdEncoding encoding) {
  encode::require_voxels(volume, "NRRD writer");
  write_nrrd_with(volume.grid(), "uchar", content, encoding, sink, [&](ByteSink& out) { write_raw(volume, out); });
}

void write_nrrd(const DenseVolume<float>& volume, std::string_view content, ByteSink& sink, NrrdEncoding encoding,
                float scale) {
  encode::require_voxels(volume, "NRRD writer");
  write_nrrd_with(volume.grid(), "float", content, encoding, sink, [&](ByteSink& out) { write_raw(volume, out, scale); });
}

}  // namespace voxd
