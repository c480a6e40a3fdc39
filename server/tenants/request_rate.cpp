#include "server/tenants/request_rate.h"

#include <algorithm>
#include <cmath>

namespace voxd::server {

std::optional<int> RequestRate::take(const std::string& tenant, std::uint64_t per_minute,
                                     std::chrono::steady_clock::time_point now) {
  if (per_minute == 0) return std::nullopt;
  const double capacity = static_cast<double>(per_minute);
  const double per_second = capacity / 60.0;
  std::lock_guard lock(mutex_);
  auto [it, fresh] = buckets_.try_emplace(tenant, Bucket{capacity, now});
  Bucket& b = it->second;
  if (!fresh) {
    const double elapsed = std::chrono::duration<double>(now - b.at).count();
    b.tokens = std::min(capacity, b.tokens + std::max(0.0, elapsed) * per_second);
    b.at = now;
  }
  if (b.tokens >= 1.0) {
    b.tokens -= 1.0;
    return std::nullopt;
  }
  return std::max(1, static_cast<int>(std::ceil((1.0 - b.tokens) / per_second)));
}

}  // namespace voxd::server
