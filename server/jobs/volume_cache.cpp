#include "server/jobs/volume_cache.h"

namespace voxd::server {

void VolumeCache::put(const std::string& key, std::shared_ptr<const void> item, std::size_t bytes) {
  std::lock_guard lock(mutex_);
  erase_locked(key);
  bytes_ += bytes;
  entries_.push_front({key, std::move(item), bytes});
  while (bytes_ > max_bytes_ && entries_.size() > 1) {
    bytes_ -= entries_.back().bytes;
    entries_.pop_back();
  }
}

std::shared_ptr<const void> VolumeCache::get_any(const std::string& key) {
  std::lock_guard lock(mutex_);
  for (auto it = entries_.begin(); it != entries_.end(); ++it)
    if (it->key == key) {
      entries_.splice(entries_.begin(), entries_, it);
      return it->item;
    }
  return nullptr;
}

void VolumeCache::drop_job(const std::string& id) {
  std::lock_guard lock(mutex_);
  const std::string prefix = id + "/";
  for (auto it = entries_.begin(); it != entries_.end();) {
    if (it->key == id || it->key.rfind(prefix, 0) == 0) {
      bytes_ -= it->bytes;
      it = entries_.erase(it);
    } else {
      ++it;
    }
  }
}

void VolumeCache::erase_locked(const std::string& key) {
  for (auto it = entries_.begin(); it != entries_.end(); ++it)
    if (it->key == key) {
      bytes_ -= it->bytes;
      entries_.erase(it);
      return;
    }
}

}  // namespace voxd::server
