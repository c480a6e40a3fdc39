#include "server/jobs/background_save.h"

#include <exception>
#include <system_error>
#include <utility>

#include <spdlog/spdlog.h>

namespace voxd::server {

BackgroundSave::BackgroundSave(std::shared_ptr<std::mutex> mutex, std::unique_lock<std::mutex> lock, std::string what,
                               std::function<void()> save)
    : mutex_(std::move(mutex)), lock_(std::move(lock)) {
  // An exception must not leave the thread (that ends the process): the
  // result is only not kept.
  auto run = [what = std::move(what), save = std::move(save)] {
    try {
      save();
    } catch (const std::exception& e) {
      spdlog::warn("{}: not kept: {}", what, e.what());
    } catch (...) {
      spdlog::warn("{}: not kept", what);
    }
  };
  try {
    thread_ = std::thread(run);
  } catch (const std::system_error&) {
    run();  // no thread to be had: written now, as before
  }
}

BackgroundSave& BackgroundSave::operator=(BackgroundSave&& other) noexcept {
  if (this == &other) return *this;
  if (thread_.joinable()) thread_.join();
  thread_ = std::move(other.thread_);
  lock_ = std::move(other.lock_);  // unlocks this one's
  mutex_ = std::move(other.mutex_);
  return *this;
}

BackgroundSave::~BackgroundSave() {
  if (thread_.joinable()) thread_.join();
}

}  // namespace voxd::server
