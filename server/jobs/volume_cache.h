#pragma once
// Recently used result volumes, in memory up to a byte budget (least
// recently used first out), so streaming a fresh result reads no disk. Keys
// are the job's id for its solid and id + "/" + NAME for its layers of
// values. Thread-safe.
#include <cstddef>
#include <list>
#include <memory>
#include <mutex>
#include <string>

namespace voxd::server {

class VolumeCache {
 public:
  explicit VolumeCache(std::size_t max_bytes) : max_bytes_(max_bytes) {}

  static std::string layer_key(const std::string& id, const std::string& name) { return id + "/" + name; }

  void put(const std::string& key, std::shared_ptr<const void> item, std::size_t bytes);
  template <class T>
  std::shared_ptr<const T> get(const std::string& key) {
    return std::static_pointer_cast<const T>(get_any(key));
  }
  // Drops a job's solid and all its layers.
  void drop_job(const std::string& id);

 private:
  struct Entry {
    std::string key;
    std::shared_ptr<const void> item;
    std::size_t bytes;
  };
  std::shared_ptr<const void> get_any(const std::string& key);
  void erase_locked(const std::string& key);

  const std::size_t max_bytes_;
  std::mutex mutex_;
  std::list<Entry> entries_;  // most recently used first
  std::size_t bytes_ = 0;
};

}  // namespace voxd::server
