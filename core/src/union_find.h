#pragma once
// A union-find over 32-bit ids 0..n-1 (path halving). join keeps the
// smaller root as the root, so a set's root is its smallest id: callers
// that number things in scan order find each set's first member there.
#include <algorithm>
#include <cstdint>
#include <numeric>
#include <vector>

namespace voxd::detail {

struct UnionFind {
  std::vector<std::uint32_t> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
  std::uint32_t find(std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void join(std::uint32_t a, std::uint32_t b) {
    a = find(a), b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

}  // namespace voxd::detail
