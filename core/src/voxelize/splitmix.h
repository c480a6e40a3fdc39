#pragma once
// splitmix64 (Steele, Lea & Flood 2014): the one generator behind every
// seeded pattern of the engine (stochastic coverage rays, palette sample
// points, Perlin permutations). Positions hashed from (seed, indices) need
// no shared state between threads and repeat on any machine, and on the GPU.
#include <cstdint>

#include "voxelize/host_device.h"

namespace voxd::detail {

// The finalizer: a well-mixed 64-bit hash of z (+ the golden-ratio step).
VOXD_HD inline std::uint64_t splitmix_hash(std::uint64_t z) {
  z += 0x9e3779b97f4a7c15ull;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

// The sequence form: advances `state` and returns the next value.
VOXD_HD inline std::uint64_t splitmix64(std::uint64_t& state) {
  const std::uint64_t z = splitmix_hash(state);
  state += 0x9e3779b97f4a7c15ull;
  return z;
}

// A double in [0, 1) from the top 53 bits.
VOXD_HD inline double unit_interval(std::uint64_t h) { return static_cast<double>(h >> 11) * (1.0 / 9007199254740992.0); }

}  // namespace voxd::detail
