#pragma once
// One voxel row's coverage from the sorted crossings of its k x k rays: each
// ray's crossings pair into inside runs (an odd count, from an open mesh,
// leaves the last one unpaired); a run adds +w where it starts and -w where it
// ends, so after sorting these events the inside share f is constant between
// two of them. Shared by the coverage voxelizer and the benchmark that checks
// other ray tracers against it.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

namespace voxd::detail {

using RunEvents = std::vector<std::pair<double, float>>;

// The events of the crossings [begin, end), grouped by ray and sorted along
// it, clipped to the row [0, nx] and sorted. `Crossing` has `ray` and `x`.
template <typename Crossing>
void collect_run_events(const Crossing* begin, const Crossing* end, double nx, float w, RunEvents& events) {
  events.clear();
  for (const Crossing* r = begin; r != end;) {
    const Crossing* e = r;
    while (e != end && e->ray == r->ray) ++e;
    for (const Crossing* c = r; c + 1 < e; c += 2) {
      const double x0 = std::clamp(c->x, 0.0, nx), x1 = std::clamp((c + 1)->x, 0.0, nx);
      if (x1 > x0) {
        events.emplace_back(x0, w);
        events.emplace_back(x1, -w);
      }
    }
    r = e;
  }
  std::sort(events.begin(), events.end());
}

// Exact: each voxel gets the integral of f over its extent.
inline void integrate_runs(const RunEvents& events, float* row, std::int64_t nx) {
  double f = 0.0, prev = 0.0;
  for (const auto& [x, delta] : events) {
    if (f > 0.0 && x > prev) {
      const auto i0 = static_cast<std::int64_t>(std::floor(prev));
      const auto i1 = std::min(static_cast<std::int64_t>(std::floor(x)), nx - 1);
      if (i0 == i1) {
        row[i0] += static_cast<float>(f * (x - prev));
      } else {
        row[i0] += static_cast<float>(f * (static_cast<double>(i0 + 1) - prev));
        for (std::int64_t i = i0 + 1; i < i1; ++i) row[i] += static_cast<float>(f);
        row[i1] += static_cast<float>(f * (x - static_cast<double>(i1)));
      }
    }
    f += delta;
    prev = x;
  }
}

// The paper's point sampling: m points per voxel at (i + (p + 1/2) / m),
// each counted with the share of rays inside there.
inline void sample_runs(const RunEvents& events, float* row, std::int64_t nx, int m) {
  double f = 0.0, prev = 0.0;
  for (const auto& [x, delta] : events) {
    if (f > 0.0 && x > prev) {
      // Points s = i * m + p with prev <= (s + 1/2) / m < x.
      const auto s0 = static_cast<std::int64_t>(std::ceil(prev * m - 0.5));
      const auto s1 = static_cast<std::int64_t>(std::ceil(x * m - 0.5));  // exclusive
      for (std::int64_t s = std::max<std::int64_t>(s0, 0); s < s1 && s < nx * m; ++s) row[s / m] += static_cast<float>(f / m);
    }
    f += delta;
    prev = x;
  }
}

// Rounding of the float sums can step a hair outside [0, 1].
inline void clamp_coverage(float* row, std::int64_t nx) {
  for (std::int64_t i = 0; i < nx; ++i) row[i] = std::clamp(row[i], 0.0f, 1.0f);
}

}  // namespace voxd::detail
