#pragma once
// One voxel row's coverage from the sorted crossings of its k x k rays: each
// ray's crossings pair into inside runs (an odd count, from an open mesh,
// leaves the last one unpaired); a run adds +w where it starts and -w where it
// ends, so after sorting these events the inside share f is constant between
// two of them. Shared by the coverage voxelizer, the CUDA kernels
// (core/src/cuda/coverage_kernel.cu) and the benchmark that checks other ray
// tracers against it: every voxel's value is the same float sum, in the same
// order, wherever it is computed. Events are ordered by (x, delta), a total
// order over their values, so any correct sort yields the same sequence.
#include <math.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "voxelize/host_device.h"

namespace voxd::detail {

struct RunEvent {
  double x;
  float delta;
};
VOXD_HD inline bool operator<(const RunEvent& a, const RunEvent& b) {
  return a.x < b.x || (a.x == b.x && a.delta < b.delta);
}

using RunEvents = std::vector<RunEvent>;

// The run events of crossings [begin, end), grouped by ray and sorted along
// it, clipped to the row [0, nx], written to `out` (unsorted) and counted.
// `Crossing` has `ray` and `x`, `Event` has `x` and `delta`; `out` may be
// `begin` itself (event n is written after crossings up to n are read).
template <typename Crossing, typename Event>
VOXD_HD inline std::int64_t pair_runs(const Crossing* begin, const Crossing* end, double nx, float w, Event* out) {
  std::int64_t n = 0;
  for (const Crossing* r = begin; r != end;) {
    const Crossing* e = r;
    while (e != end && e->ray == r->ray) ++e;
    for (const Crossing* c = r; c + 1 < e; c += 2) {
      const double a = c->x, b = (c + 1)->x;
      const double x0 = a < 0.0 ? 0.0 : a > nx ? nx : a, x1 = b < 0.0 ? 0.0 : b > nx ? nx : b;
      if (x1 > x0) {
        out[n].x = x0, out[n].delta = w;
        out[n + 1].x = x1, out[n + 1].delta = -w;
        n += 2;
      }
    }
    r = e;
  }
  return n;
}

// Exact: each voxel gets the integral of f over its extent.
template <typename Event>
VOXD_HD inline void integrate_runs(const Event* begin, const Event* end, float* row, std::int64_t nx) {
  double f = 0.0, prev = 0.0;
  for (const Event* e = begin; e != end; ++e) {
    const double x = e->x;
    if (f > 0.0 && x > prev) {
      const auto i0 = static_cast<std::int64_t>(floor(prev));
      const auto last = static_cast<std::int64_t>(floor(x));
      const std::int64_t i1 = last < nx - 1 ? last : nx - 1;
      if (i0 == i1) {
        row[i0] += static_cast<float>(f * (x - prev));
      } else {
        row[i0] += static_cast<float>(f * (static_cast<double>(i0 + 1) - prev));
        for (std::int64_t i = i0 + 1; i < i1; ++i) row[i] += static_cast<float>(f);
        row[i1] += static_cast<float>(f * (x - static_cast<double>(i1)));
      }
    }
    f += e->delta;
    prev = x;
  }
}

// The paper's point sampling: m points per voxel at (i + (p + 1/2) / m),
// each counted with the share of rays inside there.
template <typename Event>
VOXD_HD inline void sample_runs(const Event* begin, const Event* end, float* row, std::int64_t nx, int m) {
  double f = 0.0, prev = 0.0;
  for (const Event* e = begin; e != end; ++e) {
    const double x = e->x;
    if (f > 0.0 && x > prev) {
      // Points s = i * m + p with prev <= (s + 1/2) / m < x.
      const auto s0 = static_cast<std::int64_t>(ceil(prev * m - 0.5));
      const auto s1 = static_cast<std::int64_t>(ceil(x * m - 0.5));  // exclusive
      for (std::int64_t s = s0 > 0 ? s0 : 0; s < s1 && s < nx * m; ++s) row[s / m] += static_cast<float>(f / m);
    }
    f += e->delta;
    prev = x;
  }
}

// Rounding of the float sums can step a hair outside [0, 1].
VOXD_HD inline void clamp_coverage(float* row, std::int64_t nx) {
  for (std::int64_t i = 0; i < nx; ++i) row[i] = row[i] < 0.0f ? 0.0f : row[i] > 1.0f ? 1.0f : row[i];
}

// The CPU's form: the events of a column's crossings (sorted by ray, then
// x), sorted.
template <typename Crossing>
void collect_run_events(const Crossing* begin, const Crossing* end, double nx, float w, RunEvents& events) {
  events.resize(static_cast<std::size_t>(end - begin));
  events.resize(static_cast<std::size_t>(pair_runs(begin, end, nx, w, events.data())));
  std::sort(events.begin(), events.end());
}
inline void integrate_runs(const RunEvents& events, float* row, std::int64_t nx) {
  integrate_runs(events.data(), events.data() + events.size(), row, nx);
}
inline void sample_runs(const RunEvents& events, float* row, std::int64_t nx, int m) {
  sample_runs(events.data(), events.data() + events.size(), row, nx, m);
}

}  // namespace voxd::detail
