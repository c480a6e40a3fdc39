#include "server/http/volume_stream.h"

#include <zlib.h>

#include <httplib.h>
#include <spdlog/spdlog.h>

#include "voxd/byte_sink.h"

namespace voxd::server {
namespace {

// Thrown when the client went away: stops the encoder without a log line.
struct ClientGone {};

class HttpChunkSink final : public ByteSink {
 public:
  HttpChunkSink(httplib::DataSink& out, bool gzip, Metrics* metrics) : out_(out), gzip_(gzip), metrics_(metrics) {
    if (gzip_ && deflateInit2(&z_, Z_BEST_SPEED, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) != Z_OK)
      throw std::runtime_error("deflateInit2 failed");
  }
  ~HttpChunkSink() override {
    if (gzip_) deflateEnd(&z_);
  }
  using ByteSink::write;
  void write(std::span<const std::uint8_t> bytes) override {
    if (!gzip_) {
      send(reinterpret_cast<const char*>(bytes.data()), bytes.size());
      return;
    }
    deflate_all(bytes.data(), bytes.size(), Z_NO_FLUSH);
  }
  void finish() {
    if (gzip_) deflate_all(nullptr, 0, Z_FINISH);
  }

 private:
  void deflate_all(const std::uint8_t* data, std::size_t size, int flush) {
    z_.next_in = const_cast<Bytef*>(data);
    z_.avail_in = static_cast<uInt>(size);
    int rc;
    do {
      z_.next_out = buffer_;
      z_.avail_out = sizeof buffer_;
      rc = deflate(&z_, flush);
      if (rc == Z_STREAM_ERROR) throw std::runtime_error("deflate failed");
      send(reinterpret_cast<const char*>(buffer_), sizeof buffer_ - z_.avail_out);
    } while (z_.avail_out == 0 || (flush == Z_FINISH && rc != Z_STREAM_END));
  }
  void send(const char* data, std::size_t size) {
    if (size == 0) return;
    if (!out_.write(data, size)) throw ClientGone{};
    if (metrics_) metrics_->add_bytes_out(size);
  }

  httplib::DataSink& out_;
  bool gzip_;
  Metrics* metrics_;
  z_stream z_{};
  std::uint8_t buffer_[1 << 16];
};

}  // namespace

void stream_volume(httplib::Response& res, std::shared_ptr<const BitVolume> volume, VolumeFormat format,
                   EncodeOptions options, bool gzip, const std::string& filename, Metrics* metrics) {
  res.set_header("Content-Disposition", "attachment; filename=\"" + filename + "\"");
  if (gzip) res.set_header("Content-Encoding", "gzip");
  res.set_chunked_content_provider(media_type(format), [volume, format, options, gzip, metrics](std::size_t, httplib::DataSink& out) {
    try {
      auto sink = std::make_unique<HttpChunkSink>(out, gzip, metrics);
      encode_volume(*volume, format, *sink, options);
      sink->finish();
      out.done();
      return true;
    } catch (const ClientGone&) {
      return false;
    } catch (const std::exception& e) {
      spdlog::error("streaming a volume failed: {}", e.what());
      return false;
    }
  });
}

}  // namespace voxd::server
