// Issue #5: trace the stochastic coverage rays with Embree 3 (all hits along
// each ray, sorted and de-duplicated) instead of the engine's scan
// conversion, and measure both: time and exactness. No engine code or test
// calls Embree for coverage (only this benchmark does).
//
// Finding (2026-11, shared 2-core VM): Embree's tracing is several times
// faster than the engine's crossing part, but not exact. Every seed at 512^3
// gives rays with a doubled hit on a shared edge at two different float t
// (so no equal-t dedup can merge it: odd count, inverted inside runs, up to
// hundreds of voxels off by a whole ray's share) and grazing rays whose
// crossing count differs, in ROBUST mode and without it. "Keep the faster
// that stays exact" keeps the engine's scan conversion.
//
// Same input as coverage_bench: the benchmark mesh (1.1M triangles),
// benchmark_grid(res, 1), k x k = 4 x 4 rays per voxel column along x,
// CoverageSampling::stochastic with seed 1 (the exactness pass also seeds 2
// and 3, and a non-ROBUST scene).
//
// The engine's fixed-point quantization, triangle binning and crossing test
// are used from core/src (internal headers, on this benchmark's include
// path); its ray placement and run integration are replicated around them
// (namespace `replica`), so the ray part can be timed alone. The replica is
// checked against voxelize_coverage: it must give the same volume bit for
// bit, which is what makes its per-ray crossings a fair reference and its
// crossing-only timing a fair isolation of the engine's ray part.
//
// Embree is given the engine's own quantized vertices and ray positions (the
// 2^-20 voxel lattice), in voxel units centred on the grid to keep float
// rounding smallest, as one shared-vertex triangle geometry in a
// RTC_SCENE_FLAG_ROBUST scene. An intersection filter records every hit
// (t, sign of Ng.x) and rejects it, so traversal continues; per ray the hits
// are sorted by t and hits at equal t with the same facing (one surface
// crossing through a shared edge or vertex) merged into one.
//
// Benchmarks (real time, and CPU time of the whole process, all threads; both
// sides use every core: the engine and the tracing through voxd's
// parallel_for over rows, Embree's BVH build through its TBB pool):
//  BM_EngineStochastic     voxelize_coverage, the whole call (as coverage_bench)
//  BM_ReplicaWhole         the replica, whole call (must match the line above)
//  BM_ReplicaCrossings     the replica's ray part only: binning, crossings,
//                          per-row sort; no output volume, no integration
//  BM_EmbreeBuild          vertex conversion + device + scene build (BVH)
//  BM_EmbreeTrace1/16      all-hits tracing of every ray of the grid with
//                          rtcIntersect1 / rtcIntersect16 (one column's 4 x 4
//                          rays per packet), sorted + de-duplicated crossings;
//                          scene prebuilt
//  BM_EmbreeWhole          build + trace16 + the same integration into a
//                          fresh float volume: compares with the whole call
//  BM_EmbreeExactness      one pass; counters: rays whose crossing count or
//                          parity differs from the engine's, per dedup rule
//                          (facing: the timed rule; naive: equal t only;
//                          none; tol: |dt| <= 1e-4 voxel, a fudge that would
//                          merge genuinely close crossings), and the
//                          per-voxel coverage difference
//
// Run: build/bench/coverage_embree_bench --benchmark_min_time=0.01
// (--benchmark_filter=-BM_EmbreeExactness for the timings alone).
#include <embree3/rtcore.h>

#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench_mesh.h"
#include "voxd/voxelize/coverage.h"
#include "voxelize/coverage_runs.h"
#include "voxelize/fixed_point_mesh.h"
#include "voxelize/row_rays.h"
#include "voxelize/splitmix.h"
#include "voxelize/triangle_bins.h"
#include "voxd/grid.h"
#include "voxd/parallel.h"

namespace voxd::bench {
namespace {

constexpr std::uint64_t kSeed = 1;  // CoverageOptions' default

// ---------------------------------------------------------------------------
// The engine's fixed-point mesh, binning and exact crossings (core/src
// internals, on this benchmark's include path), and a replica of
// voxelize/coverage.cpp's ray placement and run integration around them.
namespace replica {

using detail::FixedMesh;
using detail::FixedPoint;
using detail::kFixedOne;
using Bins = detail::TriangleBins;
using Crossing = detail::RayCrossing;
using detail::splitmix_hash;
using detail::unit_interval;

// The stochastic ray position of ray a * kk + b of column j, row k, in fixed
// point (u = y, v = z): CoverageVoxelizer::ray_position.
inline void ray_position(std::uint64_t seed, int kk, std::int64_t j, std::int64_t k, int a, int b, std::int64_t& pu,
                         std::int64_t& pv) {
  const std::uint64_t ray = static_cast<std::uint64_t>(k) << 20 ^ static_cast<std::uint64_t>(a * kk + b);
  const std::uint64_t h =
      splitmix_hash(seed ^ splitmix_hash(static_cast<std::uint64_t>(j) * 0x100000001b3ull ^ splitmix_hash(ray)));
  const double one = static_cast<double>(kFixedOne);
  pu = j * kFixedOne + static_cast<std::int64_t>(std::floor(((a + unit_interval(h)) / kk - 0.5) * one));
  pv = k * kFixedOne + static_cast<std::int64_t>(std::floor(((b + unit_interval(splitmix_hash(h))) / kk - 0.5) * one));
}

class Voxelizer {
 public:
  Voxelizer(const Mesh& mesh, const Grid& grid, int k, std::uint64_t seed)
      : mesh_(&mesh), fixed_(mesh, grid), grid_(grid), k_(k), seed_(seed) {}

  std::int64_t per_chunk(int threads) const { return std::max<std::int64_t>(1, grid_.dims.z / (threads * 8)); }
  Bins bins(int threads) const { return detail::bin_triangles(fixed_, 2, grid_.dims.z, per_chunk(threads), 1, threads); }

  // Row k's crossings, sorted by (column, ray, x).
  void row_crossings(const Bins& bins, std::int64_t chunk, std::int64_t k, std::vector<Crossing>& out) const {
    out.clear();
    for (std::uint32_t t = bins.offsets[static_cast<std::size_t>(chunk)];
         t < bins.offsets[static_cast<std::size_t>(chunk) + 1]; ++t)
      detail::cross_row_rays(fixed_, bins.triangles[t], k, 0, grid_.dims.y, k_ * k_,
                             [&](std::int64_t j, int r, std::int64_t& pu, std::int64_t& pv) {
                               ray_position(seed_, k_, j, k, r / k_, r % k_, pu, pv);
                             },
                             out);
    detail::sort_crossings(out);
  }

  // A sorted row of crossings into the row's voxels, as the engine's
  // fill_column does (voxelize/coverage_runs.h).
  void fill_row(const std::vector<Crossing>& crossings, float* slab, detail::RunEvents& events) const {
    for (std::size_t c = 0; c < crossings.size();) {
      std::size_t e = c;
      while (e < crossings.size() && crossings[e].column == crossings[c].column) ++e;
      fill_column(crossings.data() + c, crossings.data() + e, slab + static_cast<std::int64_t>(crossings[c].column) * grid_.dims.x,
                  events);
      c = e;
    }
  }

  void fill_column(const Crossing* begin, const Crossing* end, float* row, detail::RunEvents& events) const {
    detail::collect_run_events(begin, end, static_cast<double>(grid_.dims.x), 1.0f / static_cast<float>(k_ * k_), events);
    if (events.empty()) return;
    detail::integrate_runs(events, row, grid_.dims.x);
    detail::clamp_coverage(row, grid_.dims.x);
  }

  const Mesh& mesh() const { return *mesh_; }
  const FixedMesh& fixed() const { return fixed_; }
  const Grid& grid() const { return grid_; }
  int k() const { return k_; }
  std::uint64_t seed() const { return seed_; }

 private:
  const Mesh* mesh_;
  FixedMesh fixed_;
  Grid grid_;
  int k_;
  std::uint64_t seed_;
};

}  // namespace replica

// ---------------------------------------------------------------------------
// Embree

struct Hit {
  float t;
  float ngx;  // geometric normal's x: its sign is the crossing's direction
};

// Dedup rules for the hits of one ray (sorted by t):
enum class Dedup {
  facing,   // merge equal t with the same sign of Ng.x (the rule used for timing)
  naive,    // merge equal t whatever the facing (the literal "dedup at equal t")
  none,     // keep every hit
  tol,      // merge |dt| <= 1e-4 voxel with the same facing
};

struct HitContext {
  RTCIntersectContext ctx;
  std::vector<Hit>* lanes;  // per ray id
};

void record_all_hits(const RTCFilterFunctionNArguments* args) {
  auto* hc = reinterpret_cast<HitContext*>(args->context);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    const unsigned id = RTCRayN_id(args->ray, args->N, i);
    hc->lanes[id].push_back({RTCRayN_tfar(args->ray, args->N, i), RTCHitN_Ng_x(args->hit, args->N, i)});
    args->valid[i] = 0;  // reject: traversal goes on to the next hit
  }
}

// Sorted, de-duplicated crossings of one ray appended to `out` (x in the
// engine's convention: voxel i spans [i, i + 1)).
inline void emit(std::vector<Hit>& hits, double x0, std::int32_t column, std::int32_t ray, Dedup rule,
                 std::vector<replica::Crossing>& out) {
  std::sort(hits.begin(), hits.end(), [](const Hit& a, const Hit& b) { return a.t < b.t; });
  for (std::size_t h = 0; h < hits.size(); ++h) {
    if (h > 0 && rule != Dedup::none) {
      const Hit& p = hits[h - 1];
      const bool same_t = rule == Dedup::tol ? hits[h].t - p.t <= 1e-4f : hits[h].t == p.t;
      const bool same_facing = rule == Dedup::naive || ((hits[h].ngx > 0) == (p.ngx > 0));
      if (same_t && same_facing) continue;
    }
    out.push_back({column, ray, x0 + static_cast<double>(hits[h].t)});
  }
}

class EmbreeTracer {
 public:
  EmbreeTracer(const replica::Voxelizer& v, bool robust) : v_(v) {
    const Grid& g = v.grid();
    cx_ = static_cast<double>(g.dims.x / 2);
    cy_ = static_cast<double>(g.dims.y / 2);
    cz_ = static_cast<double>(g.dims.z / 2);
    device_ = rtcNewDevice(nullptr);
    if (!device_) throw std::runtime_error("rtcNewDevice failed");
    scene_ = rtcNewScene(device_);
    rtcSetSceneFlags(scene_, robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
    rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_MEDIUM);
    RTCGeometry geom = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
    const Mesh& m = v.mesh();
    auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                           3 * sizeof(float), m.vertices.size()));
    auto* ib = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                              3 * sizeof(unsigned), m.triangles.size()));
    const double one = static_cast<double>(replica::kFixedOne);
    parallel_for(0, static_cast<std::int64_t>(m.vertices.size()), 1 << 16, 0, [&](std::int64_t b, std::int64_t e) {
      for (std::int64_t i = b; i < e; ++i) {
        const replica::FixedPoint q = v.fixed().vertex(static_cast<std::uint32_t>(i));
        vb[3 * i + 0] = static_cast<float>(static_cast<double>(q[0]) / one - cx_);
        vb[3 * i + 1] = static_cast<float>(static_cast<double>(q[1]) / one - cy_);
        vb[3 * i + 2] = static_cast<float>(static_cast<double>(q[2]) / one - cz_);
      }
    });
    std::memcpy(ib, m.triangles.data(), m.triangles.size() * 3 * sizeof(unsigned));
    rtcSetGeometryIntersectFilterFunction(geom, record_all_hits);
    rtcCommitGeometry(geom);
    rtcAttachGeometry(scene_, geom);
    rtcReleaseGeometry(geom);
    rtcCommitScene(scene_);
  }
  ~EmbreeTracer() {
    rtcReleaseScene(scene_);
    rtcReleaseDevice(device_);
  }
  EmbreeTracer(const EmbreeTracer&) = delete;
  EmbreeTracer& operator=(const EmbreeTracer&) = delete;

  // Row k's crossings, sorted by (column, ray, x), for every ray of every
  // column of the row. packet: 1 (rtcIntersect1) or 16 (rtcIntersect16).
  void row_crossings(std::int64_t k, int packet, Dedup rule, std::vector<replica::Crossing>& out) const {
    out.clear();
    const Grid& g = v_.grid();
    const int kk = v_.k();
    const int per_column = kk * kk;
    const double one = static_cast<double>(replica::kFixedOne);
    const float org_x = static_cast<float>(-cx_ - 2.0);
    const double x0 = static_cast<double>(org_x) + cx_ + 0.5;
    const float tfar = static_cast<float>(g.dims.x + 4);
    std::vector<Hit> lanes[16];
    HitContext hc;
    rtcInitIntersectContext(&hc.ctx);
    hc.ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    hc.lanes = lanes;
    // Rays in order (j, a, b), in packets of up to `packet`.
    const std::int64_t total = g.dims.y * per_column;
    for (std::int64_t r0 = 0; r0 < total; r0 += packet) {
      const int n = static_cast<int>(std::min<std::int64_t>(packet, total - r0));
      std::int32_t column[16], ray[16];
      float oy[16], oz[16];
      for (int l = 0; l < n; ++l) {
        const std::int64_t r = r0 + l;
        column[l] = static_cast<std::int32_t>(r / per_column);
        ray[l] = static_cast<std::int32_t>(r % per_column);
        std::int64_t pu, pv;
        replica::ray_position(v_.seed(), kk, column[l], k, ray[l] / kk, ray[l] % kk, pu, pv);
        oy[l] = static_cast<float>(static_cast<double>(pu) / one - cy_);
        oz[l] = static_cast<float>(static_cast<double>(pv) / one - cz_);
        lanes[l].clear();
      }
      if (packet == 1) {
        RTCRayHit rh;
        rh.ray.org_x = org_x;
        rh.ray.org_y = oy[0];
        rh.ray.org_z = oz[0];
        rh.ray.tnear = 0.0f;
        rh.ray.dir_x = 1.0f;
        rh.ray.dir_y = 0.0f;
        rh.ray.dir_z = 0.0f;
        rh.ray.time = 0.0f;
        rh.ray.tfar = tfar;
        rh.ray.mask = 0xFFFFFFFFu;
        rh.ray.id = 0;
        rh.ray.flags = 0;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(scene_, &hc.ctx, &rh);
      } else {
        alignas(64) RTCRayHit16 rh;
        alignas(64) int valid[16];
        for (int l = 0; l < 16; ++l) {
          valid[l] = l < n ? -1 : 0;
          rh.ray.org_x[l] = org_x;
          rh.ray.org_y[l] = l < n ? oy[l] : 0.0f;
          rh.ray.org_z[l] = l < n ? oz[l] : 0.0f;
          rh.ray.tnear[l] = 0.0f;
          rh.ray.dir_x[l] = 1.0f;
          rh.ray.dir_y[l] = 0.0f;
          rh.ray.dir_z[l] = 0.0f;
          rh.ray.time[l] = 0.0f;
          rh.ray.tfar[l] = tfar;
          rh.ray.mask[l] = 0xFFFFFFFFu;
          rh.ray.id[l] = static_cast<unsigned>(l);
          rh.ray.flags[l] = 0;
          rh.hit.geomID[l] = RTC_INVALID_GEOMETRY_ID;
          rh.hit.instID[0][l] = RTC_INVALID_GEOMETRY_ID;
        }
        rtcIntersect16(valid, scene_, &hc.ctx, &rh);
      }
      for (int l = 0; l < n; ++l)
        if (!lanes[l].empty()) emit(lanes[l], x0, column[l], ray[l], rule, out);
    }
  }

  // Raw hits of one row, per ray (for the exactness pass).
  void row_hits(std::int64_t k, std::vector<std::vector<Hit>>& hits, double& x0_out) const {
    const Grid& g = v_.grid();
    const int kk = v_.k();
    const int per_column = kk * kk;
    hits.assign(static_cast<std::size_t>(g.dims.y * per_column), {});
    const double one = static_cast<double>(replica::kFixedOne);
    const float org_x = static_cast<float>(-cx_ - 2.0);
    x0_out = static_cast<double>(org_x) + cx_ + 0.5;
    HitContext hc;
    rtcInitIntersectContext(&hc.ctx);
    for (std::int64_t r = 0; r < g.dims.y * per_column; ++r) {
      hc.lanes = &hits[static_cast<std::size_t>(r)];
      std::int64_t pu, pv;
      const int ray = static_cast<int>(r % per_column);
      replica::ray_position(v_.seed(), kk, r / per_column, k, ray / kk, ray % kk, pu, pv);
      RTCRayHit rh{};
      rh.ray.org_x = org_x;
      rh.ray.org_y = static_cast<float>(static_cast<double>(pu) / one - cy_);
      rh.ray.org_z = static_cast<float>(static_cast<double>(pv) / one - cz_);
      rh.ray.dir_x = 1.0f;
      rh.ray.tfar = static_cast<float>(g.dims.x + 4);
      rh.ray.mask = 0xFFFFFFFFu;
      rh.ray.id = 0;
      rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      rtcIntersect1(scene_, &hc.ctx, &rh);
    }
  }

 private:
  const replica::Voxelizer& v_;
  double cx_, cy_, cz_;
  RTCDevice device_;
  RTCScene scene_;
};

// ---------------------------------------------------------------------------
// Shared state per (resolution, k)

struct Setup {
  Grid grid;
  std::unique_ptr<replica::Voxelizer> v;
};
Setup& setup(std::int64_t res, int k) {
  static std::mutex mu;
  static std::vector<std::pair<std::pair<std::int64_t, int>, std::unique_ptr<Setup>>> cache;
  std::lock_guard<std::mutex> lock(mu);
  for (auto& [key, s] : cache)
    if (key.first == res && key.second == k) return *s;
  auto s = std::make_unique<Setup>();
  s->grid = benchmark_grid(res);
  s->v = std::make_unique<replica::Voxelizer>(benchmark_mesh(), s->grid, k, kSeed);
  cache.emplace_back(std::make_pair(res, k), std::move(s));
  return *cache.back().second;
}

CoverageOptions stochastic(int k) {
  CoverageOptions o;
  o.sampling = CoverageSampling::stochastic;
  o.rays = k;
  o.seed = kSeed;
  return o;
}

DenseVolume<float> replica_volume(const replica::Voxelizer& v, int threads) {
  const Grid& g = v.grid();
  DenseVolume<float> out(g, 0.0f);
  const std::int64_t per_chunk = v.per_chunk(threads);
  const replica::Bins bins = v.bins(threads);
  parallel_for(0, g.dims.z, per_chunk, threads, [&](std::int64_t k0, std::int64_t k1) {
    std::vector<replica::Crossing> crossings;
    detail::RunEvents events;
    for (std::int64_t k = k0; k < k1; ++k) {
      v.row_crossings(bins, k0 / per_chunk, k, crossings);
      v.fill_row(crossings, out.slab(k), events);
    }
  });
  return out;
}

DenseVolume<float> embree_volume(const replica::Voxelizer& v, const EmbreeTracer& tracer, int threads) {
  const Grid& g = v.grid();
  DenseVolume<float> out(g, 0.0f);
  const std::int64_t per_chunk = v.per_chunk(threads);
  parallel_for(0, g.dims.z, per_chunk, threads, [&](std::int64_t k0, std::int64_t k1) {
    std::vector<replica::Crossing> crossings;
    detail::RunEvents events;
    for (std::int64_t k = k0; k < k1; ++k) {
      tracer.row_crossings(k, 16, Dedup::facing, crossings);
      v.fill_row(crossings, out.slab(k), events);
    }
  });
  return out;
}

double total(const DenseVolume<float>& c) {
  double s = 0;
  for (float x : c.values()) s += x;
  return s;
}

// ---------------------------------------------------------------------------
// Benchmarks

void BM_EngineStochastic(benchmark::State& state) {
  const Setup& s = setup(state.range(0), static_cast<int>(state.range(1)));
  DenseVolume<float> c;
  for (auto _ : state) {
    c = voxelize_coverage(benchmark_mesh(), s.grid, stochastic(static_cast<int>(state.range(1))));
    benchmark::DoNotOptimize(c.values().data());
  }
  state.counters["coverage_voxels"] = total(c);
}

void BM_ReplicaWhole(benchmark::State& state) {
  const Setup& s = setup(state.range(0), static_cast<int>(state.range(1)));
  DenseVolume<float> c;
  for (auto _ : state) {
    c = replica_volume(*s.v, default_thread_count());
    benchmark::DoNotOptimize(c.values().data());
  }
  state.counters["coverage_voxels"] = total(c);
}

void BM_ReplicaCrossings(benchmark::State& state) {
  const Setup& s = setup(state.range(0), static_cast<int>(state.range(1)));
  const int threads = default_thread_count();
  std::atomic<std::int64_t> count{0};
  for (auto _ : state) {
    count = 0;
    const std::int64_t per_chunk = s.v->per_chunk(threads);
    const replica::Bins bins = s.v->bins(threads);
    parallel_for(0, s.grid.dims.z, per_chunk, threads, [&](std::int64_t k0, std::int64_t k1) {
      std::vector<replica::Crossing> crossings;
      std::int64_t n = 0;
      for (std::int64_t k = k0; k < k1; ++k) {
        s.v->row_crossings(bins, k0 / per_chunk, k, crossings);
        n += static_cast<std::int64_t>(crossings.size());
        benchmark::DoNotOptimize(crossings.data());
      }
      count += n;
    });
  }
  state.counters["crossings"] = static_cast<double>(count.load());
}

void BM_EmbreeBuild(benchmark::State& state) {
  const Setup& s = setup(state.range(0), static_cast<int>(state.range(1)));
  for (auto _ : state) {
    EmbreeTracer t(*s.v, true);
    benchmark::DoNotOptimize(&t);
  }
}

void trace_all(benchmark::State& state, int packet) {
  const Setup& s = setup(state.range(0), static_cast<int>(state.range(1)));
  const EmbreeTracer tracer(*s.v, true);
  const int threads = default_thread_count();
  std::atomic<std::int64_t> count{0};
  for (auto _ : state) {
    count = 0;
    parallel_for(0, s.grid.dims.z, s.v->per_chunk(threads), threads, [&](std::int64_t k0, std::int64_t k1) {
      std::vector<replica::Crossing> crossings;
      std::int64_t n = 0;
      for (std::int64_t k = k0; k < k1; ++k) {
        tracer.row_crossings(k, packet, Dedup::facing, crossings);
        n += static_cast<std::int64_t>(crossings.size());
        benchmark::DoNotOptimize(crossings.data());
      }
      count += n;
    });
  }
  state.counters["crossings"] = static_cast<double>(count.load());
  state.counters["rays"] = static_cast<double>(s.grid.dims.y * s.grid.dims.z * state.range(1) * state.range(1));
}
void BM_EmbreeTrace1(benchmark::State& state) { trace_all(state, 1); }
void BM_EmbreeTrace16(benchmark::State& state) { trace_all(state, 16); }

void BM_EmbreeWhole(benchmark::State& state) {
  const Setup& s = setup(state.range(0), static_cast<int>(state.range(1)));
  DenseVolume<float> c;
  for (auto _ : state) {
    const EmbreeTracer tracer(*s.v, true);
    c = embree_volume(*s.v, tracer, default_thread_count());
    benchmark::DoNotOptimize(c.values().data());
  }
  state.counters["coverage_voxels"] = total(c);
}

// One pass: per ray, the engine's (replica's) crossings against Embree's,
// under each dedup rule; per voxel, the engine's coverage against the
// coverage integrated from Embree's crossings (facing rule). Range(2): 1 =
// ROBUST scene, 0 = default flags; range(3): the seed. Each mismatching ray
// is printed on stderr with the engine's crossings and Embree's raw hits.
void BM_EmbreeExactness(benchmark::State& state) {
  const Setup& s = setup(state.range(0), static_cast<int>(state.range(1)));
  const bool robust = state.range(2) != 0;
  const auto seed = static_cast<std::uint64_t>(state.range(3));
  const int threads = default_thread_count();
  const replica::Voxelizer v(benchmark_mesh(), s.grid, static_cast<int>(state.range(1)), seed);
  const int per_column = v.k() * v.k();
  constexpr int kRules = 4;
  struct Tally {
    std::int64_t rays = 0, engine_odd = 0;
    std::int64_t count_diff[kRules] = {}, odd[kRules] = {}, parity_diff[kRules] = {}, even_diff[kRules] = {};
    double max_dx = 0;  // equal counts (facing rule): largest |x_embree - x_engine|, voxels
  };
  for (auto _ : state) {
    CoverageOptions o = stochastic(v.k());
    o.seed = seed;
    const DenseVolume<float> engine = voxelize_coverage(benchmark_mesh(), s.grid, o);
    const DenseVolume<float> rep = replica_volume(v, threads);
    std::int64_t replica_diff = 0;
    for (std::size_t i = 0; i < engine.values().size(); ++i) replica_diff += engine.values()[i] != rep.values()[i];

    const EmbreeTracer tracer(v, robust);
    const replica::Bins bins = v.bins(threads);
    const std::int64_t per_chunk = v.per_chunk(threads);
    DenseVolume<float> emb(s.grid, 0.0f);
    std::mutex mu;
    Tally all;
    parallel_for(0, s.grid.dims.z, per_chunk, threads, [&](std::int64_t k0, std::int64_t k1) {
      Tally t;
      std::vector<replica::Crossing> ref, mine[kRules];
      std::vector<std::vector<Hit>> hits;
      detail::RunEvents events;
      std::vector<std::int64_t> ref_count, mine_count;
      for (std::int64_t k = k0; k < k1; ++k) {
        v.row_crossings(bins, k0 / per_chunk, k, ref);
        double x0 = 0;
        tracer.row_hits(k, hits, x0);
        for (int r = 0; r < kRules; ++r) {
          mine[r].clear();
          for (std::size_t i = 0; i < hits.size(); ++i) {
            std::vector<Hit> h = hits[i];
            if (!h.empty())
              emit(h, x0, static_cast<std::int32_t>(static_cast<std::int64_t>(i) / per_column),
                   static_cast<std::int32_t>(static_cast<std::int64_t>(i) % per_column), static_cast<Dedup>(r), mine[r]);
          }
        }
        v.fill_row(mine[static_cast<int>(Dedup::facing)], emb.slab(k), events);
        // Per-ray counts.
        const std::size_t nrays = hits.size();
        ref_count.assign(nrays, 0);
        for (const auto& c : ref) ++ref_count[static_cast<std::size_t>(c.column) * per_column + static_cast<std::size_t>(c.ray)];
        t.rays += static_cast<std::int64_t>(nrays);
        for (std::size_t i = 0; i < nrays; ++i) t.engine_odd += ref_count[i] & 1;
        for (int r = 0; r < kRules; ++r) {
          mine_count.assign(nrays, 0);
          for (const auto& c : mine[r]) ++mine_count[static_cast<std::size_t>(c.column) * per_column + static_cast<std::size_t>(c.ray)];
          for (std::size_t i = 0; i < nrays; ++i) {
            if (mine_count[i] == ref_count[i]) continue;
            ++t.count_diff[r];
            if (r == static_cast<int>(Dedup::facing) || r == static_cast<int>(Dedup::none)) {
              // Each mismatching ray on stderr: the engine's crossings, Embree's raw hits.
              char buf[160];
              std::snprintf(buf, sizeof buf, "mismatch rule=%s row=%lld column=%zu ray=%zu engine:", r == 0 ? "facing" : "none",
                            static_cast<long long>(k), i / static_cast<std::size_t>(per_column),
                            i % static_cast<std::size_t>(per_column));
              std::string line(buf);
              for (const auto& c : ref)
                if (static_cast<std::size_t>(c.column) * per_column + static_cast<std::size_t>(c.ray) == i) {
                  std::snprintf(buf, sizeof buf, " %.9f", c.x);
                  line.append(buf);
                }
              line.append(" embree(x, Ng.x):");
              std::vector<Hit> h = hits[i];
              std::sort(h.begin(), h.end(), [](const Hit& p, const Hit& q) { return p.t < q.t; });
              for (const Hit& x : h) {
                std::snprintf(buf, sizeof buf, " (%.9f, %+.3g)", x0 + static_cast<double>(x.t), static_cast<double>(x.ngx));
                line.append(buf);
              }
              std::lock_guard<std::mutex> lock(mu);
              std::fprintf(stderr, "%s\n", line.c_str());
            }
            t.odd[r] += mine_count[i] & 1;
            if ((mine_count[i] ^ ref_count[i]) & 1) ++t.parity_diff[r]; else ++t.even_diff[r];
          }
        }
        // Positions where the counts agree (facing rule); both lists sorted by (column, ray, x).
        const auto& m = mine[static_cast<int>(Dedup::facing)];
        std::size_t a = 0, b = 0;
        while (a < ref.size() && b < m.size()) {
          const auto ka = static_cast<std::int64_t>(ref[a].column) * per_column + ref[a].ray;
          const auto kb = static_cast<std::int64_t>(m[b].column) * per_column + m[b].ray;
          if (ka < kb) { ++a; continue; }
          if (kb < ka) { ++b; continue; }
          std::size_t ea = a, eb = b;
          while (ea < ref.size() && static_cast<std::int64_t>(ref[ea].column) * per_column + ref[ea].ray == ka) ++ea;
          while (eb < m.size() && static_cast<std::int64_t>(m[eb].column) * per_column + m[eb].ray == kb) ++eb;
          if (ea - a == eb - b)
            for (std::size_t q = 0; q < ea - a; ++q) t.max_dx = std::max(t.max_dx, std::fabs(ref[a + q].x - m[b + q].x));
          a = ea;
          b = eb;
        }
      }
      std::lock_guard<std::mutex> lock(mu);
      all.rays += t.rays;
      all.engine_odd += t.engine_odd;
      all.max_dx = std::max(all.max_dx, t.max_dx);
      for (int r = 0; r < kRules; ++r) {
        all.count_diff[r] += t.count_diff[r];
        all.odd[r] += t.odd[r];
        all.parity_diff[r] += t.parity_diff[r];
        all.even_diff[r] += t.even_diff[r];
      }
    });
    double max_diff = 0;
    std::int64_t over_1e3 = 0, over_16th = 0;
    for (std::size_t i = 0; i < engine.values().size(); ++i) {
      const double d = std::fabs(static_cast<double>(engine.values()[i]) - static_cast<double>(emb.values()[i]));
      max_diff = std::max(max_diff, d);
      over_1e3 += d > 1e-3;
      over_16th += d >= 1.0 / per_column - 1e-6;
    }
    state.counters["rays"] = static_cast<double>(all.rays);
    state.counters["replica_voxels_differing"] = static_cast<double>(replica_diff);
    state.counters["engine_odd_rays"] = static_cast<double>(all.engine_odd);
    const char* names[kRules] = {"facing", "naive", "none", "tol"};
    for (int r = 0; r < kRules; ++r) {
      state.counters[std::string("count_diff_") + names[r]] = static_cast<double>(all.count_diff[r]);
      state.counters[std::string("odd_") + names[r]] = static_cast<double>(all.odd[r]);
      state.counters[std::string("parity_diff_") + names[r]] = static_cast<double>(all.parity_diff[r]);
      state.counters[std::string("even_diff_") + names[r]] = static_cast<double>(all.even_diff[r]);
    }
    state.counters["max_dx_voxel"] = all.max_dx;
    state.counters["voxel_max_diff"] = max_diff;
    state.counters["voxels_diff_gt_1e-3"] = static_cast<double>(over_1e3);
    state.counters["voxels_diff_ge_1_16"] = static_cast<double>(over_16th);
    state.counters["coverage_engine"] = total(engine);
    state.counters["coverage_embree"] = total(emb);
  }
}

BENCHMARK(BM_EngineStochastic)->Args({256, 4})->Args({512, 4})->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();
BENCHMARK(BM_ReplicaWhole)->Args({256, 4})->Args({512, 4})->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();
BENCHMARK(BM_ReplicaCrossings)->Args({256, 4})->Args({512, 4})->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();
BENCHMARK(BM_EmbreeBuild)->Args({256, 4})->Args({512, 4})->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();
BENCHMARK(BM_EmbreeTrace1)->Args({256, 4})->Args({512, 4})->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();
BENCHMARK(BM_EmbreeTrace16)->Args({256, 4})->Args({512, 4})->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();
BENCHMARK(BM_EmbreeWhole)->Args({256, 4})->Args({512, 4})->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();
BENCHMARK(BM_EmbreeExactness)
    ->Args({256, 4, 1, 1})
    ->Args({512, 4, 1, 1})
    ->Args({512, 4, 0, 1})
    ->Args({512, 4, 1, 2})
    ->Args({512, 4, 0, 2})
    ->Args({512, 4, 1, 3})
    ->Args({512, 4, 0, 3})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace voxd::bench
