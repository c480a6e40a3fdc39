// Build tool: compresses one web asset once, at build time, so that the
// service never compresses the page's files per request (three.core.js took
// 2.8 s a request with brotli). Writes OUT.br (brotli, best quality) and
// OUT.gz (gzip, best level); server/CMakeLists.txt assembles both into the
// binary beside the file itself.
//   voxd_precompress FILE OUT
#include <brotli/encode.h>
#include <zlib.h>

#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace {

bool write_file(const std::string& path, const std::vector<std::uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  return static_cast<bool>(out);
}

std::vector<std::uint8_t> brotli(const std::vector<std::uint8_t>& in) {
  std::vector<std::uint8_t> out(BrotliEncoderMaxCompressedSize(in.size()) + 1024);
  std::size_t size = out.size();
  if (!BrotliEncoderCompress(BROTLI_MAX_QUALITY, BROTLI_DEFAULT_WINDOW, BROTLI_MODE_TEXT, in.size(), in.data(), &size, out.data()))
    return {};
  out.resize(size);
  return out;
}

std::vector<std::uint8_t> gzip(const std::vector<std::uint8_t>& in) {
  z_stream z{};
  // windowBits 15 + 16: a gzip header and trailer, as Content-Encoding: gzip
  // means; no file name or time in the header, so the bytes are reproducible.
  if (deflateInit2(&z, Z_BEST_COMPRESSION, Z_DEFLATED, 15 + 16, 9, Z_DEFAULT_STRATEGY) != Z_OK) return {};
  std::vector<std::uint8_t> out(deflateBound(&z, in.size()) + 64);
  z.next_in = const_cast<Bytef*>(in.data());
  z.avail_in = static_cast<uInt>(in.size());
  z.next_out = out.data();
  z.avail_out = static_cast<uInt>(out.size());
  const int rc = deflate(&z, Z_FINISH);
  out.resize(z.total_out);
  deflateEnd(&z);
  return rc == Z_STREAM_END ? out : std::vector<std::uint8_t>{};
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: voxd_precompress FILE OUT\n");
    return 2;
  }
  std::ifstream in(argv[1], std::ios::binary);
  const std::vector<std::uint8_t> bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (!in.eof() && !in) {
    std::fprintf(stderr, "voxd_precompress: cannot read %s\n", argv[1]);
    return 1;
  }
  const std::vector<std::uint8_t> br = brotli(bytes), gz = gzip(bytes);
  if ((br.empty() || gz.empty()) && !bytes.empty()) {
    std::fprintf(stderr, "voxd_precompress: cannot compress %s\n", argv[1]);
    return 1;
  }
  const std::string out = argv[2];
  return write_file(out + ".br", br) && write_file(out + ".gz", gz) ? 0 : 1;
}
