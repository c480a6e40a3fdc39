#pragma once
// Streams a volume as an HTTP response: chunked transfer encoding, one chunk
// per encoder write (about a slab), gzip-compressed when the client accepts
// it. The volume is shared, so the response owns it until the last byte.
#include <memory>
#include <string>

#include "server/http/metrics.h"
#include "voxd/bit_volume.h"
#include "voxd/volume_format.h"

namespace httplib {
struct Response;
}

namespace voxd::server {

void stream_volume(httplib::Response& res, std::shared_ptr<const BitVolume> volume, VolumeFormat format,
                   EncodeOptions options, bool gzip, const std::string& filename, Metrics* metrics);

}  // namespace voxd::server
