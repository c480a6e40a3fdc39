#pragma once
// A kept result written to the job store on a thread of its own while the
// request that made it goes on (the report's regions and statistics after
// the thickness map, a large answer while it is sent): writing and syncing
// hundreds of megabytes takes about half a second that nobody need wait
// for. The write holds the result's key lock (server/jobs/key_lock.h) until
// it ends, so a second request for the same key waits for it and then
// reads the kept result rather than computing it again. Destroying this
// waits for the write. A failed write is logged; the result is then
// computed again when next asked for.
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "server/jobs/key_lock.h"

namespace voxd::server {

class BackgroundSave {
 public:
  BackgroundSave() = default;
  // Runs `save` on a thread of its own, then lets `lock` (of `key`) go.
  BackgroundSave(std::shared_ptr<KeyLock> key, std::unique_lock<KeyLock> lock, std::string what,
                 std::function<void()> save);
  BackgroundSave(BackgroundSave&&) = default;
  // Waits for this one's write first.
  BackgroundSave& operator=(BackgroundSave&& other) noexcept;
  ~BackgroundSave();

 private:
  std::thread thread_;
};

}  // namespace voxd::server
