#pragma once
// Streams a volume as an HTTP response: chunked transfer encoding, one chunk
// per encoder write (about a slab), gzip-compressed when the client accepts
// it. The volumes are shared, so the response owns them until the last byte.
#include <functional>
#include <memory>
#include <string>

#include "server/http/metrics.h"
#include "voxd/bit_volume.h"
#include "voxd/byte_sink.h"
#include "voxd/encode/volume_format.h"

namespace httplib {
struct Response;
}

namespace voxd::server {

// Streams what `encode` writes. `encode` runs later, on the connection's
// thread, so it must own (capture by shared pointer) what it encodes.
void stream_encoded(httplib::Response& res, const char* media_type, std::function<void(ByteSink&)> encode, bool gzip,
                    const std::string& filename, Metrics* metrics);

void stream_volume(httplib::Response& res, std::shared_ptr<const BitVolume> volume, VolumeFormat format,
                   EncodeOptions options, bool gzip, const std::string& filename, Metrics* metrics);
void stream_volume(httplib::Response& res, std::shared_ptr<const ValueVolume> volume, VolumeFormat format,
                   EncodeOptions options, bool gzip, const std::string& filename, Metrics* metrics);

}  // namespace voxd::server
