#pragma once
// One piece of work at a time holds the GPU: each sizes its slabs from the
// memory free when it starts, which two at once would both count.
#include <mutex>

namespace voxd::detail {

inline std::mutex& gpu_gate() {
  static std::mutex gate;
  return gate;
}

}  // namespace voxd::detail
