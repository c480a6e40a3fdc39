#include "server/jobs/job_store.h"

#include <cstring>

namespace voxd::server {

bool JobStore::load_artifact_into(const std::string& id, const std::string& key, std::span<char> out) const {
  const auto bytes = load_artifact(id, key);
  if (!bytes || bytes->size() != out.size()) return false;
  std::memcpy(out.data(), bytes->data(), out.size());
  return true;
}

ValueVolume read_stored_layer(std::string_view type, std::span<const std::uint8_t> rle) {
  if (type == "u8") return read_rle_u8(rle, kStoredVolumeLimits);
  if (type == "f32") return read_rle_f32(rle, kStoredVolumeLimits);
  if (type == "rgba8") return read_rle_rgba8(rle, kStoredVolumeLimits);
  throw std::invalid_argument("unknown stored value type '" + std::string(type) + "'");
}

}  // namespace voxd::server
