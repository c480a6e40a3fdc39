// Connected thin / thick regions by runs, as parts and voids are found
// (components.cpp): one parallel pass over the map finds each row's runs of
// selected voxels with their sums, for every query at once (the report asks
// four of a map of hundreds of megabytes); a union-find over a query's runs
// joins each
// run to the runs it touches (26-connectivity: in the row before in its
// layer, and in the three rows round it in the layer before); each
// region's sums are then gathered from its runs.
//
// Every sum is an integer, the thickness included (in fixed point, exact
// for every value the map can hold from 2^-41 to 2^30 voxels; a larger one,
// infinity too, counts as 2^30), and regions are numbered in the scan order
// of their first voxels, so the regions, their order and
// the probes' answers do not depend on the thread count or on the order in
// which runs are joined. Memory: the runs (28 bytes each; a smooth map has
// a few a row) and a union-find entry each.
#include "voxd/analysis/thickness_regions.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <unordered_map>

#include <glm/common.hpp>

#include "analysis/zero_skip.h"
#include "union_find.h"
#include "voxd/parallel.h"
#include "voxd/uncleared_vector.h"

namespace voxd {
namespace {

using Int128 = __int128;

// The fixed point of the thickness sums: 2^-64 voxels.
constexpr int kFixedBits = 64;

// v * 2^64 for a positive float v = m * 2^(e - 150) (e its biased
// exponent, m its 24-bit significand; subnormals have e = 1 and no hidden
// bit): exact from 2^-41 up, the bits below 2^-64 dropped. Values from
// 2^30 voxels up (no grid has such a wall; infinity) count as 2^30, so
// that 2^32 voxels' sum still fits.
Int128 fixed_point(float v) {
  constexpr int kMaxShift = 30 - 24 + kFixedBits;  // m < 2^24: v * 2^64 < 2^(30 + 64)
  const auto bits = std::bit_cast<std::uint32_t>(v);
  const int e = static_cast<int>(bits >> 23);
  const std::uint32_t m = (bits & 0x7fffffu) | (e ? 0x800000u : 0u);
  const int shift = std::max(e, 1) - 150 + kFixedBits;
  if (shift > kMaxShift) return Int128{1} << (30 + kFixedBits);
  return shift >= 0 ? static_cast<Int128>(m) << shift : static_cast<Int128>(m >> std::min(-shift, 31));
}

double from_fixed_point(Int128 sum) { return std::ldexp(static_cast<double>(sum), -kFixedBits); }

// A sum of fixed_point(v) over positive floats, exact as theirs, with one
// integer add a value: the significands of a stretch of values with the
// same exponent (a wall's voxels mostly read the same) are added first and
// shifted once. That is exact where fixed_point only shifts left and does
// not cap (exponents 86 to 156, 2^-41 to 2^30 voxels); other values are
// added one at a time.
class ExactSum {
 public:
  void add(float v) {
    const auto bits = std::bit_cast<std::uint32_t>(v);
    const std::uint32_t e = bits >> 23;
    if (e < kLowest || e > kHighest) {
      sum_ += fixed_point(v);
      return;
    }
    if (e != exponent_) {
      flush();
      exponent_ = e;
    }
    significands_ += (bits & 0x7fffffu) | 0x800000u;  // < 2^24 each, < 2^31 a row: no overflow
  }
  Int128 total() {
    flush();
    return sum_;
  }

 private:
  static constexpr std::uint32_t kLowest = 150 - kFixedBits;             // shift 0
  static constexpr std::uint32_t kHighest = 30 - 24 + 150;               // the last exponent not capped
  void flush() {
    if (significands_) sum_ += static_cast<Int128>(significands_) << (exponent_ - 150 + kFixedBits);
    significands_ = 0;
  }
  Int128 sum_ = 0;
  std::uint32_t exponent_ = 0;
  std::uint64_t significands_ = 0;
};

// A run of selected voxels [begin, end) of one row, and what it holds.
struct Run {
  std::int32_t begin, end;
};
struct RunSums {
  float extreme;  // the row's min (thin) or max (thick) over the run
  Int128 thickness;
};


// What a region gathers from its runs: integer sums, so any order gives the
// same region.
struct RegionSums {
  std::uint64_t voxels = 0;
  std::int64_t si = 0, sj = 0, sk = 0;
  glm::i64vec3 lo{std::numeric_limits<std::int64_t>::max()}, hi{-1};
  float extreme = 0.0f;
  Int128 thickness = 0;
};

// Adds what `more` gathered of a region to `s`: as if its runs had been
// added to `s` one by one.
void add_sums(RegionSums& s, const RegionSums& more, bool thin) {
  if (more.voxels == 0) return;
  s.extreme = s.voxels == 0 ? more.extreme : thin ? std::min(s.extreme, more.extreme) : std::max(s.extreme, more.extreme);
  s.voxels += more.voxels;
  s.si += more.si;
  s.sj += more.sj;
  s.sk += more.sk;
  s.lo = glm::min(s.lo, more.lo);
  s.hi = glm::max(s.hi, more.hi);
  s.thickness += more.thickness;
}

// Adds run r of row (j, k), whose sums are rs, to region s.
void add_run(RegionSums& s, const Run& r, const RunSums& rs, std::int64_t j, std::int64_t k, bool thin) {
  const auto n = static_cast<std::int64_t>(r.end - r.begin);
  RegionSums run;
  run.voxels = static_cast<std::uint64_t>(n);
  run.si = (static_cast<std::int64_t>(r.begin) + r.end - 1) * n / 2;
  run.sj = j * n;
  run.sk = k * n;
  run.lo = glm::i64vec3(r.begin, j, k);
  run.hi = glm::i64vec3(r.end - 1, j, k);
  run.extreme = rs.extreme;
  run.thickness = rs.thickness;
  add_sums(s, run, thin);
}

// One query's runs in scan order: row r's are [row_start[r], row_start[r + 1]).
struct QueryRuns {
  UnclearedVector<Run> runs;  // written whole, on every thread (scan_runs)
  UnclearedVector<RunSums> sums;
  UnclearedVector<std::uint64_t> row_start;

  // Once the regions are found: given back on every thread, as they were
  // written (freed on the calling thread, they were a third of the report's
  // serial time in this stage).
  void free_memory(int threads) {
    free_on_every_thread(runs, threads);
    free_on_every_thread(sums, threads);
    free_on_every_thread(row_start, threads);
  }
};

// Each query's runs, from one parallel pass over the map, layer by layer;
// row r = j + ny k. A voxel is read once whatever the number of queries: its
// selection mask (bit q: query q selects it) is computed, and a stretch of
// voxels with the same mask (a wall's interior) gathers its minimum,
// maximum and fixed-point sum once for every query open over it.
std::vector<QueryRuns> scan_runs(const DenseVolume<float>& thickness, const std::vector<ThicknessRegionQuery>& queries,
                                 int threads) {
  const glm::i64vec3 d = thickness.grid().dims;
  if (d.x > std::numeric_limits<std::int32_t>::max())
    throw std::length_error("find_thickness_regions: rows longer than 2^31 voxels");
  constexpr std::size_t kMaxQueries = 32;  // bits of a mask
  if (queries.size() > kMaxQueries) throw std::length_error("find_thickness_regions: more than 32 queries at once");
  const std::size_t nq = queries.size();
  const std::int64_t rows = d.y * d.z;
  // A query's selection, as the bits of a mask: thin ones below their
  // threshold, thick ones above (in locals, not vectors the compiler must
  // reload after every store).
  struct Selection {
    std::array<float, kMaxQueries> below{}, above{};
    std::array<std::uint32_t, kMaxQueries> below_bit{}, above_bit{};
    std::size_t n_below = 0, n_above = 0;
    std::uint32_t mask_of(float v) const {
      std::uint32_t m = 0;
      for (std::size_t t = 0; t < n_below; ++t) m |= v < below[t] ? below_bit[t] : 0u;
      for (std::size_t t = 0; t < n_above; ++t) m |= v > above[t] ? above_bit[t] : 0u;
      return m;
    }
  };
  Selection selection;
  for (std::size_t q = 0; q < nq; ++q) {
    if (queries[q].kind == ThicknessRegionKind::thin) {
      selection.below_bit[selection.n_below] = std::uint32_t{1} << q;
      selection.below[selection.n_below++] = queries[q].threshold_voxels;
    } else {
      selection.above_bit[selection.n_above] = std::uint32_t{1} << q;
      selection.above[selection.n_above++] = queries[q].threshold_voxels;
    }
  }
  // [query][layer]
  std::vector<std::vector<std::vector<Run>>> layer_runs(nq, std::vector<std::vector<Run>>(static_cast<std::size_t>(d.z)));
  std::vector<std::vector<std::vector<RunSums>>> layer_sums(nq, std::vector<std::vector<RunSums>>(static_cast<std::size_t>(d.z)));
  std::vector<std::vector<std::uint32_t>> row_count(nq, std::vector<std::uint32_t>(static_cast<std::size_t>(rows), 0));
  parallel_for(0, d.z, 1, threads, [&](std::int64_t k0, std::int64_t k1) {
    // The run each query has open in the row (its bit set in `open`).
    struct Open {
      std::int32_t begin = 0;
      float extreme = 0.0f;
      Int128 sum = 0;
      std::uint32_t count = 0;  // the row's runs so far
    };
    const Selection select = selection;
    std::vector<Open> at(nq);
    std::vector<bool> thin(nq);
    for (std::size_t q = 0; q < nq; ++q) thin[q] = queries[q].kind == ThicknessRegionKind::thin;
    for (std::int64_t k = k0; k < k1; ++k) {
      const auto layer = static_cast<std::size_t>(k);
      for (std::int64_t j = 0; j < d.y; ++j) {
        const float* row = thickness.slab(k) + j * d.x;
        // The open runs, and the stretch of voxels since the mask last changed.
        std::uint32_t open = 0;
        float low = 0.0f, high = 0.0f;
        ExactSum sum;
        // The stretch ends before voxel `end`, where the mask becomes `next`:
        // its voxels join every open run, those not in `next` close, and
        // those new in `next` open.
        auto change = [&](std::int64_t end, std::uint32_t next) {
          const Int128 stretch_sum = open ? sum.total() : 0;
          for (std::uint32_t m = open; m;) {
            const auto q = static_cast<std::size_t>(std::countr_zero(m));
            m &= m - 1;
            Open& o = at[q];
            o.extreme = thin[q] ? std::min(o.extreme, low) : std::max(o.extreme, high);
            o.sum += stretch_sum;
            if (!(next >> q & 1u)) {
              layer_runs[q][layer].push_back({o.begin, static_cast<std::int32_t>(end)});
              layer_sums[q][layer].push_back({o.extreme, o.sum});
              ++o.count;
            }
          }
          for (std::uint32_t m = next & ~open; m;) {
            const auto q = static_cast<std::size_t>(std::countr_zero(m));
            m &= m - 1;
            at[q].begin = static_cast<std::int32_t>(end);
            at[q].extreme = thin[q] ? std::numeric_limits<float>::infinity() : -std::numeric_limits<float>::infinity();
            at[q].sum = 0;
          }
          open = next;
          low = std::numeric_limits<float>::infinity();
          high = -std::numeric_limits<float>::infinity();
          sum = ExactSum{};
        };
        for (std::int64_t i = detail::skip_zero_blocks(row, 0, d.x); i < d.x;) {
          const float v = row[i];
          if (!(v > 0.0f)) {  // selected by none (NaN neither)
            if (open) change(i, 0);
            i = detail::skip_zero_blocks(row, i + 1, d.x);
            continue;
          }
          const std::uint32_t m = select.mask_of(v);
          if (m != open) change(i, m);
          if (m) {
            low = std::min(low, v);
            high = std::max(high, v);
            sum.add(v);
          }
          ++i;
        }
        if (open) change(d.x, 0);
        for (std::size_t q = 0; q < nq; ++q) {
          row_count[q][static_cast<std::size_t>(j + d.y * k)] = at[q].count;
          at[q].count = 0;
        }
      }
    }
  });
  // Each layer's runs go after the layers before: where is summed here
  // (a layer at a time), the copies, the rows' starts within each layer
  // (and the layers' own vectors given back) go on every thread. On the
  // calling thread they were most of this stage's serial time.
  std::vector<QueryRuns> out(nq);
  std::vector<std::vector<std::uint64_t>> layer_start(nq);
  for (std::size_t q = 0; q < nq; ++q) {
    QueryRuns& r = out[q];
    layer_start[q].resize(static_cast<std::size_t>(d.z) + 1, 0);
    for (std::size_t k = 0; k < static_cast<std::size_t>(d.z); ++k)
      layer_start[q][k + 1] = layer_start[q][k] + layer_runs[q][k].size();
    const std::uint64_t total = layer_start[q].back();
    if (total > std::numeric_limits<std::uint32_t>::max())
      throw std::length_error("find_thickness_regions: more than 2^32 runs");
    r.runs.resize(static_cast<std::size_t>(total));
    r.sums.resize(static_cast<std::size_t>(total));
    r.row_start.resize(static_cast<std::size_t>(rows) + 1);
    r.row_start[0] = 0;
  }
  parallel_for(0, d.z, 1, threads, [&](std::int64_t k0, std::int64_t k1) {
    for (std::size_t q = 0; q < nq; ++q)
      for (auto k = static_cast<std::size_t>(k0); k < static_cast<std::size_t>(k1); ++k) {
        const auto at = static_cast<std::ptrdiff_t>(layer_start[q][k]);
        std::copy(layer_runs[q][k].begin(), layer_runs[q][k].end(), out[q].runs.begin() + at);
        std::copy(layer_sums[q][k].begin(), layer_sums[q][k].end(), out[q].sums.begin() + at);
        std::vector<Run>().swap(layer_runs[q][k]);
        std::vector<RunSums>().swap(layer_sums[q][k]);
        // Row r's runs end where row r + 1's start: the layer's rows summed
        // from where the layer's runs start.
        std::uint64_t end = layer_start[q][k];
        const std::size_t row0 = k * static_cast<std::size_t>(d.y);
        for (std::size_t j = 0; j < static_cast<std::size_t>(d.y); ++j) {
          end += row_count[q][row0 + j];
          out[q].row_start[row0 + j + 1] = end;
        }
      }
  });
  return out;
}

// One query's regions from its runs (and its probes' answers).
std::vector<ThicknessRegion> regions_of(const QueryRuns& found_runs, const glm::i64vec3& d, ThicknessRegionKind kind,
                                        std::uint64_t min_voxels, std::size_t voxel_count,
                                        const std::vector<std::size_t>* probes,
                                        std::vector<std::uint32_t>* probe_regions, int threads) {
  const bool thin = kind == ThicknessRegionKind::thin;
  const auto& runs = found_runs.runs;
  const auto& sums = found_runs.sums;
  const UnclearedVector<std::uint64_t>& row_start = found_runs.row_start;
  const std::uint64_t total = row_start.back();
  // Join each run with the runs it touches in rows already seen: runs of a
  // row are sorted, and touch when they overlap [begin - 1, end + 1).
  detail::UnionFind regions(static_cast<std::size_t>(total));
  auto link = [&](std::uint64_t run, std::int64_t other_row) {
    const Run& r = runs[static_cast<std::size_t>(run)];
    const auto first = runs.begin() + static_cast<std::ptrdiff_t>(row_start[static_cast<std::size_t>(other_row)]);
    const auto last = runs.begin() + static_cast<std::ptrdiff_t>(row_start[static_cast<std::size_t>(other_row) + 1]);
    auto it = std::lower_bound(first, last, r.begin - 1, [](const Run& a, std::int64_t x) { return a.end <= x; });
    for (; it != last && it->begin < r.end + 1; ++it)
      regions.join(static_cast<std::uint32_t>(run), static_cast<std::uint32_t>(it - runs.begin()));
  };
  // Row (j, k)'s runs joined to row j - 1's and, with `below`, to layer k - 1's.
  const auto link_row = [&](std::int64_t j, std::int64_t k, bool below) {
    const std::int64_t row = j + d.y * k;
    for (std::uint64_t run = row_start[static_cast<std::size_t>(row)]; run < row_start[static_cast<std::size_t>(row) + 1]; ++run) {
      if (j > 0) link(run, row - 1);
      if (below)
        for (std::int64_t jj = std::max<std::int64_t>(0, j - 1); jj <= std::min(d.y - 1, j + 1); ++jj) link(run, jj + d.y * (k - 1));
    }
  };
  // The layers in runs of layers, one a thread, joined apart: a run of
  // layers joins only its own runs' sets, so the threads never touch one
  // set. Then each run of layers' first layer to the layer below, in order.
  // A set's root is its smallest run whatever the order of the joins
  // (UnionFind), so the regions are the same on any number of threads.
  const std::int64_t parts = std::clamp<std::int64_t>(d.z / 2, 1, threads > 0 ? threads : default_thread_count());
  parallel_for(0, parts, 1, threads, [&](std::int64_t p0, std::int64_t p1) {
    for (std::int64_t p = p0; p < p1; ++p)
      for (std::int64_t k = d.z * p / parts; k < d.z * (p + 1) / parts; ++k)
        for (std::int64_t j = 0; j < d.y; ++j) link_row(j, k, k > d.z * p / parts);
  });
  for (std::int64_t p = 1; p < parts; ++p) {
    const std::int64_t k = d.z * p / parts;
    for (std::int64_t j = 0; j < d.y; ++j) {
      const std::int64_t row = j + d.y * k;
      for (std::uint64_t run = row_start[static_cast<std::size_t>(row)]; run < row_start[static_cast<std::size_t>(row) + 1]; ++run)
        for (std::int64_t jj = std::max<std::int64_t>(0, j - 1); jj <= std::min(d.y - 1, j + 1); ++jj) link(run, jj + d.y * (k - 1));
    }
  }
  // Every run's root, on every thread: reading the finished forest only.
  UnclearedVector<std::uint32_t> root_of;  // written whole, on every thread
  root_of.resize(static_cast<std::size_t>(total));
  parallel_for(0, static_cast<std::int64_t>(total), std::int64_t{1} << 16, threads, [&](std::int64_t a, std::int64_t b) {
    for (auto run = static_cast<std::uint32_t>(a); run < static_cast<std::uint32_t>(b); ++run) {
      std::uint32_t x = run;
      while (regions.parent[x] != x) x = regions.parent[x];
      root_of[run] = x;
    }
  });

  // Regions are numbered in scan order, as their roots are met (a root is
  // its region's first run), and their sums gathered, in runs of layers on
  // every thread: a run of layers numbers its roots on from the count of
  // roots before it, adds its runs to their regions' sums, and those of
  // regions begun in an earlier run of layers to sums of its own, added in
  // afterwards. Sums are of integers, minima and maxima: the same in any
  // order, so the regions are the same on any number of threads. (On the
  // calling thread this was most of what was left of the stage there.)
  const std::int64_t gather_parts = std::clamp<std::int64_t>(d.z, 1, 4 * (threads > 0 ? threads : default_thread_count()));
  const auto layer_of_part = [&](std::int64_t p) { return d.z * p / gather_parts; };
  const auto first_run = [&](std::int64_t p) { return row_start[static_cast<std::size_t>(d.y * layer_of_part(p))]; };
  std::vector<std::uint64_t> first_region(static_cast<std::size_t>(gather_parts) + 1, 0);
  parallel_for(0, gather_parts, 1, threads, [&](std::int64_t p0, std::int64_t p1) {
    for (std::int64_t p = p0; p < p1; ++p) {
      std::uint64_t roots = 0;
      for (std::uint64_t run = first_run(p); run < first_run(p + 1); ++run) roots += root_of[run] == run;
      first_region[static_cast<std::size_t>(p) + 1] = roots;
    }
  });
  for (std::size_t p = 1; p < first_region.size(); ++p) first_region[p] += first_region[p - 1];
  UnclearedVector<std::uint32_t> region_of;
  region_of.resize(static_cast<std::size_t>(total));
  parallel_for(0, gather_parts, 1, threads, [&](std::int64_t p0, std::int64_t p1) {
    for (std::int64_t p = p0; p < p1; ++p) {
      auto next = static_cast<std::uint32_t>(first_region[static_cast<std::size_t>(p)]);
      const std::uint64_t begin = first_run(p);
      for (std::uint64_t run = begin; run < first_run(p + 1); ++run) {
        const std::uint32_t root = root_of[run];
        if (root == run)
          region_of[run] = next++;
        else if (root >= begin)  // numbered just now; an earlier run of layers' roots, once it is done
          region_of[run] = region_of[root];
      }
    }
  });
  UnclearedVector<RegionSums> found;  // by first voxel: the order regions are met in scan order
  assign_on_every_thread(found, static_cast<std::size_t>(first_region.back()), RegionSums{}, threads);
  std::vector<std::unordered_map<std::uint32_t, RegionSums>> begun_before(static_cast<std::size_t>(gather_parts));
  parallel_for(0, gather_parts, 1, threads, [&](std::int64_t p0, std::int64_t p1) {
    for (std::int64_t p = p0; p < p1; ++p) {
      const std::uint64_t begin = first_run(p);
      auto& earlier = begun_before[static_cast<std::size_t>(p)];
      std::uint32_t last_earlier = UINT32_MAX;
      RegionSums* last_sums = nullptr;
      for (std::int64_t k = layer_of_part(p); k < layer_of_part(p + 1); ++k)
        for (std::int64_t j = 0; j < d.y; ++j) {
          const auto row = static_cast<std::size_t>(j + d.y * k);
          for (std::uint64_t run = row_start[row]; run < row_start[row + 1]; ++run) {
            const std::uint32_t root = root_of[run];
            RegionSums* s = nullptr;
            if (root >= begin) {
              s = &found[region_of[run]];
            } else {
              const std::uint32_t region = region_of[run] = region_of[root];
              if (region != last_earlier) {
                last_earlier = region;
                last_sums = &earlier[region];  // node-based: stays put as the map grows
              }
              s = last_sums;
            }
            add_run(*s, runs[run], sums[run], j, k, thin);
          }
        }
    }
  });
  for (const auto& earlier : begun_before)
    for (const auto& [region, more] : earlier) add_sums(found[region], more, thin);

  // Those of at least min_voxels, most severe first: the thinnest (thickest)
  // extreme, then the larger region, then scan order (found's order).
  std::vector<std::uint32_t> kept;
  for (std::uint32_t f = 0; f < found.size(); ++f)
    if (found[f].voxels >= min_voxels) kept.push_back(f);
  std::stable_sort(kept.begin(), kept.end(), [&](std::uint32_t a, std::uint32_t b) {
    const RegionSums &x = found[a], &y = found[b];
    if (x.extreme != y.extreme) return thin ? x.extreme < y.extreme : x.extreme > y.extreme;
    if (x.voxels != y.voxels) return x.voxels > y.voxels;
    return a < b;
  });
  std::vector<ThicknessRegion> out;
  out.reserve(kept.size());
  std::vector<std::uint32_t> rank(found.size(), 0);  // 1 + place in `out`, 0 for none
  for (const std::uint32_t f : kept) {
    const RegionSums& s = found[f];
    const double count = static_cast<double>(s.voxels);
    ThicknessRegion r;
    r.voxel_count = s.voxels;
    r.bbox_min = s.lo;
    r.bbox_max = s.hi;
    r.centroid = glm::dvec3(static_cast<double>(s.si), static_cast<double>(s.sj), static_cast<double>(s.sk)) / count;
    r.extreme_thickness = s.extreme;
    r.mean_thickness = static_cast<float>(from_fixed_point(s.thickness) / count);
    rank[f] = static_cast<std::uint32_t>(out.size()) + 1;
    out.push_back(r);
  }
  if (probes && probe_regions) {
    probe_regions->assign(probes->size(), 0);
    for (std::size_t p = 0; p < probes->size(); ++p) {
      const std::size_t idx = (*probes)[p];
      if (idx >= voxel_count) continue;
      const auto row = static_cast<std::int64_t>(idx / static_cast<std::size_t>(d.x));
      const auto i = static_cast<std::int32_t>(idx % static_cast<std::size_t>(d.x));
      const auto first = runs.begin() + static_cast<std::ptrdiff_t>(row_start[static_cast<std::size_t>(row)]);
      const auto last = runs.begin() + static_cast<std::ptrdiff_t>(row_start[static_cast<std::size_t>(row) + 1]);
      const auto it = std::upper_bound(first, last, i, [](std::int32_t x, const Run& a) { return x < a.end; });
      if (it != last && it->begin <= i) (*probe_regions)[p] = rank[region_of[static_cast<std::size_t>(it - runs.begin())]];
    }
  }
  return out;
}

}  // namespace

std::vector<ThicknessRegion> find_thickness_regions(const DenseVolume<float>& thickness, ThicknessRegionKind kind,
                                                    float threshold_voxels, std::uint64_t min_voxels,
                                                    const std::vector<std::size_t>* probes,
                                                    std::vector<std::uint32_t>* probe_regions, int threads) {
  std::vector<QueryRuns> runs = scan_runs(thickness, {{kind, threshold_voxels}}, threads);
  std::vector<ThicknessRegion> regions = regions_of(runs[0], thickness.grid().dims, kind, min_voxels,
                                                    thickness.values().size(), probes, probe_regions, threads);
  runs[0].free_memory(threads);
  return regions;
}

std::vector<std::vector<ThicknessRegion>> find_thickness_regions(const DenseVolume<float>& thickness,
                                                                 const std::vector<ThicknessRegionQuery>& queries,
                                                                 std::uint64_t min_voxels, int threads) {
  std::vector<QueryRuns> runs = scan_runs(thickness, queries, threads);
  std::vector<std::vector<ThicknessRegion>> out;
  out.reserve(queries.size());
  for (std::size_t q = 0; q < queries.size(); ++q) {
    out.push_back(regions_of(runs[q], thickness.grid().dims, queries[q].kind, min_voxels, thickness.values().size(),
                             nullptr, nullptr, threads));
    runs[q].free_memory(threads);
  }
  return out;
}

}  // namespace voxd
