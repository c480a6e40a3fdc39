// Welding by exact position: an open-addressing hash table keyed by the bit
// patterns of the coordinates. Soups of a million triangles are the common
// input, so the table is flat (no node allocation) and each lookup's slot is
// prefetched a few vertices ahead, which hides most of the cache misses of a
// table larger than the cache.
#include <algorithm>
#include <bit>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "voxd/error.h"
#include "voxd/mesh_report.h"

namespace voxd {
namespace {

constexpr std::uint32_t kEmpty = std::numeric_limits<std::uint32_t>::max();

struct PositionBits {
  std::uint32_t x, y, z;
  bool operator==(const PositionBits&) const = default;
};

// -0.0 and 0.0 are the same point.
std::uint32_t canonical_bits(float f) {
  const auto bits = std::bit_cast<std::uint32_t>(f);
  return bits == 0x80000000u ? 0u : bits;
}

PositionBits position_bits(const glm::vec3& p) {
  return {canonical_bits(p.x), canonical_bits(p.y), canonical_bits(p.z)};
}

std::uint64_t hash_of(const PositionBits& k) {
  std::uint64_t h = (std::uint64_t{k.x} << 32 | k.y) * 0x9E3779B97F4A7C15ull;
  h ^= (std::uint64_t{k.z} + 0x632BE59BD9B4E019ull) * 0xC2B2AE3D27D4EB4Full;
  h ^= h >> 31;
  return h * 0xD6E8FEB86659FD93ull;
}

// The key sits in the slot itself, so a lookup touches one cache line.
struct Slot {
  PositionBits key;
  std::uint32_t vertex = kEmpty;
};

class PositionTable {
 public:
  explicit PositionTable(std::size_t expected_unique) { resize(std::bit_ceil(std::max<std::size_t>(64, 2 * expected_unique))); }

  void prefetch(const PositionBits& key) const { __builtin_prefetch(&slots_[slot_of(key)]); }

  // Returns the vertex already stored under `key`, or stores and returns `fresh`.
  std::uint32_t find_or_insert(const PositionBits& key, std::uint32_t fresh) {
    for (std::size_t i = slot_of(key);; i = (i + 1) & mask_) {
      Slot& slot = slots_[i];
      if (slot.vertex == kEmpty) {
        slot = {key, fresh};
        if (++size_ * 10 > slots_.size() * 7) grow();
        return fresh;
      }
      if (slot.key == key) return slot.vertex;
    }
  }

 private:
  std::size_t slot_of(const PositionBits& key) const { return static_cast<std::size_t>(hash_of(key) >> shift_); }

  void resize(std::size_t capacity) {
    slots_.assign(capacity, Slot{});
    mask_ = capacity - 1;
    shift_ = 64 - std::countr_zero(capacity);
  }

  void grow() {
    std::vector<Slot> old = std::move(slots_);
    resize(old.size() * 2);
    for (const Slot& s : old) {
      if (s.vertex == kEmpty) continue;
      std::size_t i = slot_of(s.key);
      while (slots_[i].vertex != kEmpty) i = (i + 1) & mask_;
      slots_[i] = s;
    }
  }

  std::vector<Slot> slots_;
  std::size_t mask_ = 0;
  int shift_ = 64;
  std::size_t size_ = 0;
};

}  // namespace

Mesh weld_vertices(const Mesh& mesh) {
  const std::size_t n = mesh.vertices.size();
  Mesh welded;
  welded.vertices.reserve(n / 4);
  std::vector<std::uint32_t> remap(n);
  // Soups (the input that needs welding most) share each position about six
  // times; an indexed mesh makes the table grow once or twice, which is cheap.
  PositionTable table(n / 4);
  constexpr std::size_t kLookahead = 16;
  for (std::size_t i = 0; i < n; ++i) {
    if (i + kLookahead < n) table.prefetch(position_bits(mesh.vertices[i + kLookahead]));
    const auto fresh = static_cast<std::uint32_t>(welded.vertices.size());
    const std::uint32_t v = table.find_or_insert(position_bits(mesh.vertices[i]), fresh);
    if (v == fresh) welded.vertices.push_back(mesh.vertices[i]);
    remap[i] = v;
  }
  welded.triangles.resize(mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t v = mesh.triangles[t][c];
      if (v >= n)
        throw Error(ErrorCode::invalid_argument, "triangle " + std::to_string(t) + " refers to vertex " +
                                                     std::to_string(v) + " of " + std::to_string(n));
      welded.triangles[t][c] = remap[v];
    }
  }
  return welded;
}

}  // namespace voxd
