#include "server/http/volume_stream.h"

#include "server/log_safe.h"

#include <httplib.h>
#include <spdlog/spdlog.h>

namespace voxd::server {
namespace {

// Thrown when the client went away: stops the encoder without a log line.
struct ClientGone {};

class HttpChunkSink final : public ByteSink {
 public:
  HttpChunkSink(httplib::DataSink& out, Metrics* metrics) : out_(out), metrics_(metrics) {}
  using ByteSink::write;
  void write(std::span<const std::uint8_t> bytes) override {
    if (bytes.empty()) return;
    if (!out_.write(reinterpret_cast<const char*>(bytes.data()), bytes.size())) throw ClientGone{};
    if (metrics_) metrics_->add_bytes_out(bytes.size());
  }

 private:
  httplib::DataSink& out_;
  Metrics* metrics_;
};

}  // namespace

void stream_encoded(httplib::Response& res, const char* media_type, std::function<void(ByteSink&)> encode, bool gzip,
                    const std::string& filename, Metrics* metrics) {
  res.set_header("Content-Disposition", "attachment; filename=\"" + filename + "\"");
  if (gzip) res.set_header("Content-Encoding", "gzip");
  res.set_chunked_content_provider(media_type, [encode = std::move(encode), gzip, metrics](std::size_t, httplib::DataSink& out) {
    try {
      HttpChunkSink chunks(out, metrics);
      if (gzip) {
        GzipSink compressed(chunks);
        encode(compressed);
        compressed.finish();
      } else {
        encode(chunks);
      }
      out.done();
      return true;
    } catch (const ClientGone&) {
      return false;
    } catch (const std::exception& e) {
      spdlog::error("streaming a volume failed: {}", log_safe(e.what()));
      return false;
    }
  });
}

void stream_volume(httplib::Response& res, std::shared_ptr<const BitVolume> volume, VolumeFormat format,
                   EncodeOptions options, bool gzip, const std::string& filename, Metrics* metrics) {
  stream_encoded(
      res, media_type(format),
      [volume = std::move(volume), format, options](ByteSink& sink) { encode_volume(*volume, format, sink, options); },
      gzip, filename, metrics);
}

void stream_volume(httplib::Response& res, std::shared_ptr<const ValueVolume> volume, VolumeFormat format,
                   EncodeOptions options, bool gzip, const std::string& filename, Metrics* metrics) {
  stream_encoded(
      res, media_type(format),
      [volume = std::move(volume), format, options](ByteSink& sink) { encode_volume(*volume, format, sink, options); },
      gzip, filename, metrics);
}

}  // namespace voxd::server
