#pragma once
// The memory the service's work may take at once. Each piece of work reserves
// its estimated peak before it starts: a submission while its upload is
// decoded, a job from acceptance to its end (its decoded mesh waits in the
// queue, then its volumes and analyses), an analysis asked for later while
// it is computed. Work that does not fit now is refused (HTTP 429 with
// Retry-After), never started in the hope memory will do; the service's
// peak stays under the budget plus its fixed overhead and the result cache.
#include <cstdint>
#include <mutex>
#include <stdexcept>
#include <string>

namespace voxd::server {

// Work refused because the memory budget is taken now: HTTP 429.
class MemoryBusy : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
  static constexpr int kRetryAfterSeconds = 5;
};

class MemoryBudget {
 public:
  explicit MemoryBudget(std::uint64_t total) : total_(total) {}
  MemoryBudget(const MemoryBudget&) = delete;
  MemoryBudget& operator=(const MemoryBudget&) = delete;

  class Reservation {
   public:
    Reservation() = default;
    Reservation(Reservation&& other) noexcept : budget_(other.budget_), bytes_(other.bytes_) { other.budget_ = nullptr; }
    Reservation& operator=(Reservation&& other) noexcept {
      if (this != &other) {
        release();
        budget_ = other.budget_;
        bytes_ = other.bytes_;
        other.budget_ = nullptr;
      }
      return *this;
    }
    ~Reservation() { release(); }
    void release() {
      if (budget_) budget_->give_back(bytes_);
      budget_ = nullptr;
    }
    std::uint64_t bytes() const { return budget_ ? bytes_ : 0; }

   private:
    friend class MemoryBudget;
    Reservation(MemoryBudget* budget, std::uint64_t bytes) : budget_(budget), bytes_(bytes) {}
    MemoryBudget* budget_ = nullptr;
    std::uint64_t bytes_ = 0;
  };

  // Reserves `bytes` for `what` ("the job", "this analysis"): throws
  // voxd::Error limit_exceeded when it could never fit, MemoryBusy when it
  // does not fit now.
  Reservation reserve(std::uint64_t bytes, const std::string& what);

  std::uint64_t total() const { return total_; }
  std::uint64_t used() const {
    std::lock_guard lock(mutex_);
    return used_;
  }

 private:
  void give_back(std::uint64_t bytes) {
    std::lock_guard lock(mutex_);
    used_ -= bytes;
  }

  const std::uint64_t total_;
  mutable std::mutex mutex_;
  std::uint64_t used_ = 0;
};

// The physical memory this process may use: the cgroup's limit when one is
// set (a container), else the machine's memory.
std::uint64_t available_memory();

}  // namespace voxd::server
