#pragma once
// A kept result written to the job store on a thread of its own while the
// request that made it goes on (the report's regions and statistics after
// the thickness map, a volume's encoding): writing and syncing hundreds of
// megabytes takes about half a second that the computation need not wait
// for. The write is waited for when this is destroyed, on the thread that
// started it, which until then also holds the result's key lock, so a
// second request for the same key waits and then reads the kept result
// rather than computing it again. A failed write is logged; the result is
// then computed again when next asked for.
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

namespace voxd::server {

class BackgroundSave {
 public:
  BackgroundSave() = default;
  // Runs `save` on a thread of its own, holding `lock` (of `mutex`) until
  // it has ended.
  BackgroundSave(std::shared_ptr<std::mutex> mutex, std::unique_lock<std::mutex> lock, std::string what,
                 std::function<void()> save);
  BackgroundSave(BackgroundSave&&) = default;
  // Waits for this one's write first.
  BackgroundSave& operator=(BackgroundSave&& other) noexcept;
  ~BackgroundSave();

 private:
  // Destroyed from the last: the thread joined, then the lock, then its mutex.
  std::shared_ptr<std::mutex> mutex_;
  std::unique_lock<std::mutex> lock_;
  std::thread thread_;
};

}  // namespace voxd::server
