#include "voxd/byte_sink.h"

#include <cerrno>
#include <algorithm>
#include <cstring>
#include <stdexcept>

#include <zlib.h>

#include "voxd/error.h"

namespace voxd {

FileSink::FileSink(const std::string& path) : path_(path), file_(std::fopen(path.c_str(), "wb")) {
  if (!file_) throw Error(ErrorCode::io_error, "cannot open '" + path + "' for writing: " + std::strerror(errno));
  std::setvbuf(file_, nullptr, _IOFBF, 1 << 20);
}

FileSink::~FileSink() {
  if (file_) std::fclose(file_);
}

void FileSink::write(std::span<const std::uint8_t> bytes) {
  if (bytes.empty()) return;
  if (!file_) throw Error(ErrorCode::io_error, "write to closed file '" + path_ + "'");
  if (std::fwrite(bytes.data(), 1, bytes.size(), file_) != bytes.size())
    throw Error(ErrorCode::io_error, "cannot write '" + path_ + "': " + std::strerror(errno));
}

void FileSink::close() {
  if (!file_) return;
  const int rc = std::fclose(file_);
  file_ = nullptr;
  if (rc != 0) throw Error(ErrorCode::io_error, "cannot finish writing '" + path_ + "': " + std::strerror(errno));
}

struct GzipSink::Stream {
  explicit Stream(ByteSink& sink) : out(sink), buffer(std::size_t{1} << 16) {}
  ByteSink& out;
  z_stream z{};
  bool finished = false;
  std::vector<std::uint8_t> buffer;

  void deflate_all(const std::uint8_t* data, std::size_t size, int flush) {
    z.next_in = const_cast<Bytef*>(data);
    z.avail_in = static_cast<uInt>(size);
    int rc;
    do {
      z.next_out = buffer.data();
      z.avail_out = static_cast<uInt>(buffer.size());
      rc = deflate(&z, flush);
      if (rc == Z_STREAM_ERROR) throw std::runtime_error("gzip compression failed (deflate)");
      const std::size_t produced = buffer.size() - z.avail_out;
      if (produced > 0) out.write(buffer.data(), produced);
    } while (z.avail_out == 0 || (flush == Z_FINISH && rc != Z_STREAM_END));
  }
};

GzipSink::GzipSink(ByteSink& out, int level) : stream_(std::make_unique<Stream>(out)) {
  // windowBits 15 + 16: a gzip header and trailer instead of zlib's.
  if (deflateInit2(&stream_->z, level, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) != Z_OK)
    throw std::runtime_error("cannot start gzip compression (deflateInit2)");
}

GzipSink::~GzipSink() { deflateEnd(&stream_->z); }

void GzipSink::write(std::span<const std::uint8_t> bytes) {
  if (stream_->finished) throw std::logic_error("gzip stream written after finish()");
  // zlib counts input in uInt: feed very large writes in pieces.
  constexpr std::size_t kPiece = std::size_t{1} << 30;
  for (std::size_t at = 0; at < bytes.size(); at += kPiece)
    stream_->deflate_all(bytes.data() + at, std::min(kPiece, bytes.size() - at), Z_NO_FLUSH);
}

void GzipSink::finish() {
  if (stream_->finished) return;
  stream_->deflate_all(nullptr, 0, Z_FINISH);
  stream_->finished = true;
}

}  // namespace voxd
