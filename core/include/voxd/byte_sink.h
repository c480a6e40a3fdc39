#pragma once
// Where encoders write: a file, a memory buffer, or (in the server) an HTTP
// chunked stream. Encoders call write() once per slab or so, never with the
// whole volume, so a sink can forward data as it is produced.
#include <cstdint>
#include <cstdio>
#include <span>
#include <string>
#include <memory>
#include <vector>

namespace voxd {

class ByteSink {
 public:
  virtual ~ByteSink() = default;
  virtual void write(std::span<const std::uint8_t> bytes) = 0;
  void write(const void* data, std::size_t size) {
    write(std::span<const std::uint8_t>(static_cast<const std::uint8_t*>(data), size));
  }
};

class VectorSink final : public ByteSink {
 public:
  using ByteSink::write;
  void write(std::span<const std::uint8_t> bytes) override { data.insert(data.end(), bytes.begin(), bytes.end()); }
  std::vector<std::uint8_t> data;
};

// Collects the bytes in a string, the type an HTTP body and a kept result
// are: a result of hundreds of megabytes (a thickness volume) is not copied
// once more at the end. Reserve `data` when the size is known.
class StringSink final : public ByteSink {
 public:
  using ByteSink::write;
  void write(std::span<const std::uint8_t> bytes) override {
    data.append(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  }
  std::string data;
};

// Writes to a file; throws Error(io_error) on failure. close() reports a
// failed flush; the destructor closes silently.
class FileSink final : public ByteSink {
 public:
  explicit FileSink(const std::string& path);
  ~FileSink() override;
  FileSink(const FileSink&) = delete;
  FileSink& operator=(const FileSink&) = delete;
  using ByteSink::write;
  void write(std::span<const std::uint8_t> bytes) override;
  void close();

 private:
  std::string path_;
  std::FILE* file_ = nullptr;
};

// Compresses what it is given as one gzip member (RFC 1952) into `out`:
// NRRD's "encoding: gzip" and HTTP's Content-Encoding: gzip. finish() writes
// the trailer; without it the stream is incomplete. `level` is zlib's, 1
// (fastest, the default: volumes are large) to 9. Throws
// std::runtime_error if zlib fails (never the input's fault).
class GzipSink final : public ByteSink {
 public:
  explicit GzipSink(ByteSink& out, int level = 1);
  ~GzipSink() override;
  GzipSink(const GzipSink&) = delete;
  GzipSink& operator=(const GzipSink&) = delete;
  using ByteSink::write;
  void write(std::span<const std::uint8_t> bytes) override;
  void finish();

 private:
  struct Stream;  // zlib's state, kept out of this header
  std::unique_ptr<Stream> stream_;
};

}  // namespace voxd
