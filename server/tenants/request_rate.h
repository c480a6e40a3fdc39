#pragma once
// Each tenant's requests per minute (TenantQuotas::requests_per_minute), per
// replica: a token bucket per tenant that holds a minute's worth and fills
// at the quota's rate, so a client may burst to its quota and then go on at
// that rate.
#include <chrono>
#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <string>

namespace voxd::server {

class RequestRate {
 public:
  // Takes one request of `tenant` against `per_minute` (0: no limit).
  // Nothing when it may go on; else the seconds until it may (Retry-After).
  std::optional<int> take(const std::string& tenant, std::uint64_t per_minute,
                          std::chrono::steady_clock::time_point now = std::chrono::steady_clock::now());

 private:
  struct Bucket {
    double tokens = 0;
    std::chrono::steady_clock::time_point at;
  };
  std::mutex mutex_;
  std::map<std::string, Bucket> buckets_;
};

}  // namespace voxd::server
