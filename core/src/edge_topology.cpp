// Edge topology (voxd/edge_topology.h). By hashing: a pass over the
// triangles hashes every edge once, counting each bucket's keys; a second
// pass writes the keys in place; then each bucket's edges are counted in a
// small hash table of its own. Nothing is welded and no table is shared
// between threads. Of a welded mesh: by a counting sort of vertex indices.
#include "voxd/edge_topology.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <memory>
#include <vector>

#include <glm/geometric.hpp>

#include "voxd/parallel.h"

namespace voxd {
namespace {

constexpr int kBucketBits = 10;  // at most 1024 buckets
constexpr std::int64_t kGrain = 1 << 14;

// A vertex's 64-bit hash from its position's bits (-0.0 and 0.0 are the
// same point), computed once per corner.
std::uint64_t mix(std::uint64_t h) {
  h ^= h >> 30;
  h *= 0xBF58476D1CE4E5B9ull;
  h ^= h >> 27;
  h *= 0x94D049BB133111EBull;
  return h ^ (h >> 31);
}

std::uint32_t canonical(float f) {
  const auto bits = std::bit_cast<std::uint32_t>(f);
  return bits == 0x80000000u ? 0u : bits;
}

std::uint64_t vertex_hash(const glm::vec3& p) {
  return mix((std::uint64_t{canonical(p.x)} << 32 | canonical(p.y)) ^ mix(canonical(p.z) + 0x9E3779B97F4A7C15ull));
}

// The edge's key: a hash of its two vertices' hashes, unordered, with the
// lowest bit the direction (1 when traversed from the smaller hash).
std::uint64_t edge_key(std::uint64_t from, std::uint64_t to) {
  const bool forward = from < to;
  const std::uint64_t lo = forward ? from : to, hi = forward ? to : from;
  return (mix(lo ^ std::rotl(hi, 23) ^ 0xD6E8FEB86659FD93ull) & ~std::uint64_t{1}) | (forward ? 1u : 0u);
}

// Calls visit(key) for each edge of the triangles [t0, t1) that have three
// distinct positions, and returns six times their signed volume about `origin`.
template <class Visit>
double for_each_edge(const Mesh& mesh, std::int64_t t0, std::int64_t t1, glm::dvec3 origin, Visit&& visit) {
  double six_volume = 0.0;
  for (std::int64_t t = t0; t < t1; ++t) {
    const auto& tri = mesh.triangles[static_cast<std::size_t>(t)];
    const glm::vec3 &a = mesh.vertices[tri[0]], &b = mesh.vertices[tri[1]], &c = mesh.vertices[tri[2]];
    const std::uint64_t h[3] = {vertex_hash(a), vertex_hash(b), vertex_hash(c)};
    if (h[0] == h[1] || h[1] == h[2] || h[0] == h[2]) continue;
    for (int k = 0; k < 3; ++k) visit(edge_key(h[k], h[(k + 1) % 3]));
    const glm::dvec3 da(a), db(b), dc(c);
    six_volume += glm::dot(da - origin, glm::cross(db - da, dc - da));
  }
  return six_volume;
}

// One bucket's edges counted in an open-addressing table: each slot holds
// an edge's hash (the key less its direction bit, never 0 once set: the
// table stores it with bit 0 set), its uses and its forward uses. The
// table is cleared once and then only where a bucket wrote (a small job's
// hundred buckets would clear it a hundred times), and the edges are
// classified from the slots they took rather than a scan of every slot.
struct Counter {
  struct Slot {
    std::uint64_t edge = 0;
    std::uint32_t uses = 0, forward = 0;
  };
  std::vector<Slot> slots;
  std::vector<std::uint32_t> taken;

  void count(const std::uint64_t* first, const std::uint64_t* last, std::uint64_t& edges, std::uint64_t& boundary,
             std::uint64_t& nonmanifold, std::uint64_t& inconsistent) {
    const std::size_t n = static_cast<std::size_t>(last - first);
    if (n == 0) return;
    const std::size_t size = std::bit_ceil(2 * n);
    if (slots.size() < size) slots.assign(size, Slot{});
    const std::size_t mask = size - 1;
    taken.clear();
    for (const std::uint64_t* k = first; k < last; ++k) {
      const std::uint64_t id = *k | 1u;
      for (std::size_t i = static_cast<std::size_t>(*k >> 1) & mask;; i = (i + 1) & mask) {
        Slot& slot = slots[i];
        if (slot.edge == 0) {
          slot.edge = id;
          taken.push_back(static_cast<std::uint32_t>(i));
        } else if (slot.edge != id) {
          continue;
        }
        ++slot.uses;
        slot.forward += static_cast<std::uint32_t>(*k & 1);
        break;
      }
    }
    edges += taken.size();
    for (const std::uint32_t i : taken) {
      Slot& slot = slots[i];
      boundary += slot.uses == 1;
      nonmanifold += slot.uses > 2;
      inconsistent += slot.uses == 2 && slot.forward != 1;
      slot = Slot{};
    }
  }
};

}  // namespace

EdgeTopology count_edge_topology(const Mesh& mesh, int threads) {
  EdgeTopology out;
  const auto n = static_cast<std::int64_t>(mesh.triangles.size());
  if (n == 0) return out;
  const std::int64_t chunks = (n + kGrain - 1) / kGrain;
  // Buckets of about 256 edges, at most 1024: a small mesh's few edges
  // are not spread over a thousand tiny tables.
  const int bucket_bits = std::min(static_cast<int>(std::bit_width(static_cast<std::uint64_t>(3 * n) / 256)), kBucketBits);
  const std::size_t buckets = std::size_t{1} << bucket_bits;
  auto bucket_of = [bucket_bits](std::uint64_t key) {
    return bucket_bits == 0 ? std::size_t{0} : static_cast<std::size_t>(key >> (64 - bucket_bits));
  };

  // Pass 1: each chunk's keys (hashed once), its count per bucket, and its
  // share of the volume.
  // The keys go to plain arrays through a pointer (a vector's push_back
  // reloads its end from memory after every counted key), left
  // uninitialized until written.
  std::vector<std::uint32_t> counts(static_cast<std::size_t>(chunks) * buckets, 0);
  std::vector<double> volumes(static_cast<std::size_t>(chunks), 0.0);
  std::vector<std::unique_ptr<std::uint64_t[]>> chunk_keys(static_cast<std::size_t>(chunks));
  std::vector<std::size_t> chunk_size(static_cast<std::size_t>(chunks), 0);
  const glm::dvec3 origin(mesh.vertices[mesh.triangles[0][0]]);
  parallel_for(0, chunks, 1, threads, [&](std::int64_t c0, std::int64_t c1) {
    for (std::int64_t c = c0; c < c1; ++c) {
      std::uint32_t* count = counts.data() + static_cast<std::size_t>(c) * buckets;
      const std::int64_t t0 = c * kGrain, t1 = std::min(n, (c + 1) * kGrain);
      auto& mine = chunk_keys[static_cast<std::size_t>(c)];
      mine.reset(new std::uint64_t[static_cast<std::size_t>(3 * (t1 - t0))]);
      std::uint64_t* out = mine.get();
      volumes[static_cast<std::size_t>(c)] = for_each_edge(mesh, t0, t1, origin, [&](std::uint64_t key) {
        ++count[bucket_of(key)];
        *out++ = key;
      });
      chunk_size[static_cast<std::size_t>(c)] = static_cast<std::size_t>(out - mine.get());
    }
  });
  for (double v : volumes) out.six_volume += v;

  // Where each chunk writes in each bucket: buckets in order, chunks in
  // order within them.
  std::vector<std::size_t> bucket_start(buckets + 1, 0), at(counts.size());
  std::size_t total = 0;
  for (std::size_t b = 0; b < buckets; ++b) {
    bucket_start[b] = total;
    for (std::int64_t c = 0; c < chunks; ++c) {
      const std::size_t i = static_cast<std::size_t>(c) * buckets + b;
      at[i] = total;
      total += counts[i];
    }
  }
  bucket_start[buckets] = total;

  // Pass 2: the keys, each chunk into its own ranges.
  const std::unique_ptr<std::uint64_t[]> keys(new std::uint64_t[std::max<std::size_t>(total, 1)]);
  parallel_for(0, chunks, 1, threads, [&](std::int64_t c0, std::int64_t c1) {
    for (std::int64_t c = c0; c < c1; ++c) {
      std::size_t* cursor = at.data() + static_cast<std::size_t>(c) * buckets;
      auto& mine = chunk_keys[static_cast<std::size_t>(c)];
      for (std::size_t i = 0; i < chunk_size[static_cast<std::size_t>(c)]; ++i) {
        const std::uint64_t key = mine[i];
        keys[cursor[bucket_of(key)]++] = key;
      }
      mine.reset();
    }
  });

  // Each bucket's edges counted.
  std::atomic<std::uint64_t> edges{0}, boundary{0}, nonmanifold{0}, inconsistent{0};
  // A small mesh's buckets take less time than starting a thread for them
  // (every job counts its edges: a CAD plugin's 10,000 triangles, 30,000
  // edges, take about 0.2 ms here).
  constexpr std::size_t kEdgesPerThread = std::size_t{1} << 17;
  const int bucket_threads = total < kEdgesPerThread ? 1 : threads;
  parallel_for(0, static_cast<std::int64_t>(buckets), 16, bucket_threads, [&](std::int64_t b0, std::int64_t b1) {
    std::uint64_t ed = 0, bd = 0, nm = 0, ic = 0;
    Counter counter;
    for (std::int64_t b = b0; b < b1; ++b)
      counter.count(keys.get() + bucket_start[static_cast<std::size_t>(b)],
                    keys.get() + bucket_start[static_cast<std::size_t>(b) + 1], ed, bd, nm, ic);
    edges += ed;
    boundary += bd;
    nonmanifold += nm;
    inconsistent += ic;
  });
  out.edges = edges;
  out.boundary_edges = boundary;
  out.nonmanifold_edges = nonmanifold;
  out.inconsistent_edges = inconsistent;
  return out;
}

namespace {

bool repeats_a_vertex(const std::array<std::uint32_t, 3>& t) { return t[0] == t[1] || t[1] == t[2] || t[0] == t[2]; }

// Sorts a vertex's bucket of edges; buckets are tiny except around a fan
// centre, where insertion sort would go quadratic.
void sort_bucket(std::uint64_t* first, std::uint64_t* last) {
  if (last - first < 2) return;  // also an empty bucket of an empty array (null first)
  if (last - first > 32) {
    std::sort(first, last);
    return;
  }
  for (std::uint64_t* i = first + 1; i < last; ++i) {
    const std::uint64_t value = *i;
    std::uint64_t* j = i;
    for (; j > first && *(j - 1) > value; --j) *j = *(j - 1);
    *j = value;
  }
}

}  // namespace

EdgeTopology edge_topology_of_welded(const Mesh& welded) {
  EdgeTopology out;
  const auto n = static_cast<std::int64_t>(welded.triangles.size());
  if (n == 0) return out;
  // Six times the volume, as count_edge_topology sums it: about the first
  // corner, a chunk of kGrain triangles at a time, the chunks in order.
  const glm::dvec3 origin(welded.vertices[welded.triangles[0][0]]);
  for (std::int64_t t0 = 0; t0 < n; t0 += kGrain) {
    double chunk = 0.0;
    for (std::int64_t t = t0; t < std::min(n, t0 + kGrain); ++t) {
      const auto& tri = welded.triangles[static_cast<std::size_t>(t)];
      if (repeats_a_vertex(tri)) continue;
      const glm::dvec3 da(welded.vertices[tri[0]]), db(welded.vertices[tri[1]]), dc(welded.vertices[tri[2]]);
      chunk += glm::dot(da - origin, glm::cross(db - da, dc - da));
    }
    out.six_volume += chunk;
  }

  // Triangles that repeat a welded vertex have no area and would count one
  // edge twice in opposite directions; they take no part in the topology.
  const std::size_t vertex_count = welded.vertices.size();
  std::vector<std::size_t> bucket_start(vertex_count + 1, 0);
  for (const auto& t : welded.triangles) {
    if (repeats_a_vertex(t)) continue;
    for (int c = 0; c < 3; ++c) ++bucket_start[std::min(t[c], t[(c + 1) % 3]) + 1];
  }
  for (std::size_t v = 0; v < vertex_count; ++v) bucket_start[v + 1] += bucket_start[v];

  // Each use of an edge is stored in the bucket of its smaller vertex as
  // (larger vertex << 1 | 1 if traversed from smaller to larger).
  std::vector<std::uint64_t> uses(bucket_start[vertex_count]);
  if (uses.empty()) return out;  // no usable edge (every triangle repeats a vertex)
  std::vector<std::size_t> cursor(bucket_start.begin(), bucket_start.end() - 1);
  for (const auto& t : welded.triangles) {
    if (repeats_a_vertex(t)) continue;
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t from = t[c], to = t[(c + 1) % 3];
      const std::uint32_t low = std::min(from, to), high = std::max(from, to);
      uses[cursor[low]++] = std::uint64_t{high} << 1 | (from == low ? 1u : 0u);
    }
  }
  for (std::size_t v = 0; v < vertex_count; ++v) {
    std::uint64_t* first = uses.data() + bucket_start[v];
    std::uint64_t* const last = uses.data() + bucket_start[v + 1];
    sort_bucket(first, last);
    while (first < last) {
      const std::uint64_t edge = *first >> 1;
      std::uint64_t count = 0, forward = 0;
      for (; first < last && (*first >> 1) == edge; ++first) {
        ++count;
        forward += *first & 1;
      }
      ++out.edges;
      if (count == 1) ++out.boundary_edges;
      else if (count > 2) ++out.nonmanifold_edges;
      else if (forward != 1) ++out.inconsistent_edges;
    }
  }
  return out;
}

}  // namespace voxd
