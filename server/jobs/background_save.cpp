#include "server/jobs/background_save.h"

#include <exception>
#include <system_error>
#include <utility>

#include <spdlog/spdlog.h>

namespace voxd::server {

BackgroundSave::BackgroundSave(std::shared_ptr<KeyLock> key, std::unique_lock<KeyLock> lock, std::string what,
                               std::function<void()> save) {
  auto held = std::make_shared<std::unique_lock<KeyLock>>(std::move(lock));
  // An exception must not leave the thread (that ends the process): the
  // result is only not kept.
  auto run = [key = std::move(key), held, what = std::move(what), save = std::move(save)] {
    try {
      save();
    } catch (const std::exception& e) {
      spdlog::warn("{}: not kept: {}", what, e.what());
    } catch (...) {
      spdlog::warn("{}: not kept", what);
    }
    if (held->owns_lock()) held->unlock();
  };
  try {
    thread_ = std::thread(run);
  } catch (const std::system_error&) {
    run();  // no thread to be had: written now
  }
}

BackgroundSave& BackgroundSave::operator=(BackgroundSave&& other) noexcept {
  if (this == &other) return *this;
  if (thread_.joinable()) thread_.join();
  thread_ = std::move(other.thread_);
  return *this;
}

BackgroundSave::~BackgroundSave() {
  if (thread_.joinable()) thread_.join();
}

}  // namespace voxd::server
