#include "server/jobs/job_store.h"

namespace voxd::server {

ValueVolume read_stored_layer(std::string_view type, std::span<const std::uint8_t> rle) {
  if (type == "u8") return read_rle_u8(rle, kStoredVolumeLimits);
  if (type == "f32") return read_rle_f32(rle, kStoredVolumeLimits);
  if (type == "rgba8") return read_rle_rgba8(rle, kStoredVolumeLimits);
  throw std::invalid_argument("unknown stored value type '" + std::string(type) + "'");
}

}  // namespace voxd::server
