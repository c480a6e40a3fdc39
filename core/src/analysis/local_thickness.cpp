// Local thickness: every filled voxel is a ball centre; balls are painted
// largest first and each voxel keeps the value of the first ball that covers
// it, which is the largest. See voxd/analysis/local_thickness.h for why this is exact
// and fast.
#include "voxd/analysis/local_thickness.h"
#include "voxd/detail/local_thickness_tuning.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <memory>
#include <mutex>

#include "analysis/ball_painting.h"
#include "analysis/distance_transform_impl.h"
#include "analysis/zero_skip.h"
#include "voxd/error.h"
#include "voxd/parallel.h"

namespace voxd {
namespace {

using detail::inside_a_neighbour;

inline float thickness_of(std::int64_t r2) { return static_cast<float>(2.0 * std::sqrt(static_cast<double>(r2))); }

// Every filled voxel is a ball centre, handed out largest squared radius
// first. Most of the time only the largest few percent are ever needed (the
// painting stops when no voxel is left), so the centres are not sorted all at
// once: a histogram of the distance values picks a range of radii holding
// about `want` centres, one parallel scan gathers them, a counting sort
// orders them, and the next range is gathered (twice as large) only when the
// painting asks for more. Within one radius the centres stay in memory order.
struct Centre {
  std::uint64_t index;  // linear voxel index
  std::uint32_t r2;     // squared radius: the distance value there
};

class CentreQueue {
 public:
  CentreQueue(const DenseVolume<std::uint32_t>& edt, int threads, std::uint64_t first_range)
      : edt_(edt), threads_(threads) {
    const auto& d2 = edt.values();
    std::uint32_t max_d2 = 0;
    for (std::uint32_t v : d2) max_d2 = std::max(max_d2, v);
    histogram_.assign(static_cast<std::size_t>(max_d2) + 1, 0);
    for_chunks([&](std::size_t begin, std::size_t end, std::size_t) {
      std::vector<std::uint64_t> h(histogram_.size(), 0);
      for (std::size_t i = begin; i < end; ++i) ++h[d2[i]];
      std::lock_guard lock(mutex_);
      for (std::size_t l = 0; l < h.size(); ++l) histogram_[l] += h[l];
    });
    next_level_ = static_cast<std::int64_t>(max_d2);
    want_ = first_range > 0 ? first_range : std::max<std::uint64_t>(1 << 20, d2.size() / 64);
  }

  // The next centre, or false when every centre has been handed out.
  bool pop(Centre& c) {
    if (pos_ == range_.size() && !refill()) return false;
    c = range_[pos_++];
    return true;
  }

 private:
  template <typename Body>
  void for_chunks(Body&& body) {
    const std::size_t n = edt_.values().size();
    const std::size_t chunk = std::max<std::size_t>(1 << 16, n / (static_cast<std::size_t>(threads_) * 4) + 1);
    const auto chunks = static_cast<std::int64_t>((n + chunk - 1) / chunk);
    parallel_for(0, chunks, 1, threads_, [&](std::int64_t c0, std::int64_t c1) {
      for (std::int64_t c = c0; c < c1; ++c) {
        const std::size_t b = static_cast<std::size_t>(c) * chunk;
        body(b, std::min(n, b + chunk), static_cast<std::size_t>(c));
      }
    });
  }

  bool refill() {
    range_.clear();
    pos_ = 0;
    if (next_level_ < 1) return false;
    // Levels [lo, hi] holding about want_ centres (at least one level).
    const std::int64_t hi = next_level_;
    std::int64_t lo = hi;
    std::uint64_t count = histogram_[static_cast<std::size_t>(hi)];
    while (lo > 1 && count + histogram_[static_cast<std::size_t>(lo - 1)] <= want_) count += histogram_[static_cast<std::size_t>(--lo)];
    next_level_ = lo - 1;
    want_ *= 2;
    if (count == 0) return refill();
    // Gather per chunk (chunk order = memory order), then a stable counting
    // sort by level, descending.
    const auto& d2 = edt_.values();
    const std::size_t n = d2.size();
    const std::size_t chunk = std::max<std::size_t>(1 << 16, n / (static_cast<std::size_t>(threads_) * 4) + 1);
    std::vector<std::vector<Centre>> parts((n + chunk - 1) / chunk);
    const auto ulo = static_cast<std::uint32_t>(lo), uhi = static_cast<std::uint32_t>(hi);
    for_chunks([&](std::size_t begin, std::size_t end, std::size_t c) {
      for (std::size_t i = begin; i < end; ++i)
        if (d2[i] >= ulo && d2[i] <= uhi) parts[c].push_back({i, d2[i]});
    });
    std::vector<std::uint64_t> offset(static_cast<std::size_t>(hi - lo) + 2, 0);
    for (std::int64_t l = hi; l >= lo; --l) {
      offset[static_cast<std::size_t>(hi - l) + 1] = offset[static_cast<std::size_t>(hi - l)] + histogram_[static_cast<std::size_t>(l)];
    }
    range_.resize(count);
    for (const auto& part : parts)
      for (const Centre& c : part) range_[offset[hi - c.r2]++] = c;
    return true;
  }

  const DenseVolume<std::uint32_t>& edt_;
  int threads_;
  std::mutex mutex_;
  std::vector<std::uint64_t> histogram_;
  std::int64_t next_level_ = 0;  // highest level not handed out yet
  std::uint64_t want_ = 0;
  std::vector<Centre> range_;
  std::size_t pos_ = 0;
};

}  // namespace

DenseVolume<float> local_thickness(const BitVolume& solid, int threads, JobControl* control) {
  return local_thickness(solid, threads, control, detail::LocalThicknessTuning{});
}

DenseVolume<float> local_thickness(const BitVolume& solid, int threads, JobControl* control,
                                   const detail::LocalThicknessTuning& tuning) {
  const Grid& grid = solid.grid();
  const int nthreads = threads > 0 ? threads : default_thread_count();
  const detail::ProgressSpan progress{control, 0.0, 1.0};

  DenseVolume<float> out(grid, 0.0f);
  if (grid.voxel_count() == 0) return out;
  const DenseVolume<std::uint32_t> edt = detail::squared_distance_transform(solid, nthreads, progress.part(0.0, 0.3));
  progress.check_cancelled();
  CentreQueue centres(edt, nthreads, tuning.first_range);
  const detail::BallSource balls = [&](detail::Ball& ball) {
    Centre c;
    if (!centres.pop(c)) return false;
    ball = {c.index, c.r2, thickness_of(c.r2)};
    return true;
  };
  const detail::BallContained contained = [&](std::int64_t x, std::int64_t y, std::int64_t z, std::int64_t r2) {
    return inside_a_neighbour(grid.dims, x, y, z, r2, [&](std::int64_t i, std::int64_t j, std::int64_t k) {
      return static_cast<std::int64_t>(edt.slab(k)[j * grid.dims.x + i]);
    });
  };
  detail::paint_balls_largest_first(solid, out, balls, contained, {tuning.sparse_from, tuning.reach_rebuild_queries},
                                    nthreads, progress.part(0.3, 1.0));
  return out;
}

ThicknessStatistics thickness_statistics(const DenseVolume<float>& thickness, int bins, int threads) {
  if (bins < 1) throw Error(ErrorCode::invalid_argument, "thickness histogram needs at least 1 bin");
  // Two passes over the layers in parallel, each layer summed on its own and
  // the layers' sums added in layer order: the same doubles whatever the
  // thread count. The second pass sums squared deviations, which do not
  // lose precision the way sum(v^2) - n mean^2 does.
  const std::int64_t nz = thickness.grid().dims.z;
  const std::size_t layer = thickness.slab_size();
  struct Layer {
    std::uint64_t count = 0;
    float min = 0.0f, max = 0.0f;
    double sum = 0.0;
    std::vector<std::uint64_t> histogram;
  };
  std::vector<Layer> layers(static_cast<std::size_t>(nz));
  // Sums kept in locals (a store to the layer's fields each voxel is most
  // of the time otherwise) and blocks of empty voxels skipped: the same
  // values added in the same order.
  const auto n = static_cast<std::int64_t>(layer);
  parallel_for(0, nz, 1, threads, [&](std::int64_t k0, std::int64_t k1) {
    for (std::int64_t k = k0; k < k1; ++k) {
      const float* v = thickness.slab(k);
      std::uint64_t count = 0;
      float lo = 0.0f, hi = 0.0f;
      double sum = 0.0;
      for (std::int64_t i = 0; i < n;) {
        i = detail::skip_zero_blocks(v, i, n);
        for (const std::int64_t end = std::min(n, i + 8); i < end; ++i) {
          if (v[i] <= 0.0f) continue;
          if (count++ == 0) lo = hi = v[i];
          lo = std::min(lo, v[i]);
          hi = std::max(hi, v[i]);
          sum += v[i];
        }
      }
      Layer& l = layers[static_cast<std::size_t>(k)];
      l.count = count;
      l.min = lo;
      l.max = hi;
      l.sum = sum;
    }
  });
  ThicknessStatistics st;
  double sum = 0.0;
  for (const Layer& l : layers) {
    if (l.count == 0) continue;
    if (st.voxel_count == 0) st.min = l.min, st.max = l.max;
    st.min = std::min<double>(st.min, l.min);
    st.max = std::max<double>(st.max, l.max);
    sum += l.sum;
    st.voxel_count += l.count;
  }
  if (st.voxel_count == 0) return st;
  st.mean = sum / static_cast<double>(st.voxel_count);
  const double range = st.max - st.min;
  parallel_for(0, nz, 1, threads, [&](std::int64_t k0, std::int64_t k1) {
    for (std::int64_t k = k0; k < k1; ++k) {
      Layer& l = layers[static_cast<std::size_t>(k)];
      if (l.count == 0) continue;
      l.histogram.assign(static_cast<std::size_t>(bins), 0);
      std::uint64_t* histogram = l.histogram.data();
      const float* v = thickness.slab(k);
      const double mean = st.mean, min = st.min;
      double sum = 0.0;
      for (std::int64_t i = 0; i < n;) {
        i = detail::skip_zero_blocks(v, i, n);
        for (const std::int64_t end = std::min(n, i + 8); i < end; ++i) {
          if (v[i] <= 0.0f) continue;
          sum += (v[i] - mean) * (v[i] - mean);
          std::int64_t b = range > 0.0 ? static_cast<std::int64_t>((v[i] - min) / range * bins) : 0;
          b = std::clamp<std::int64_t>(b, 0, bins - 1);
          ++histogram[b];
        }
      }
      l.sum = sum;
    }
  });
  st.histogram.assign(static_cast<std::size_t>(bins), 0);
  double ss = 0.0;
  for (const Layer& l : layers) {
    if (l.count == 0) continue;
    ss += l.sum;
    for (std::size_t b = 0; b < l.histogram.size(); ++b) st.histogram[b] += l.histogram[b];
  }
  st.std_dev = std::sqrt(ss / static_cast<double>(st.voxel_count));
  return st;
}

ThicknessErrorBound thickness_error_bound() { return {1.0, 2.0}; }

std::string thickness_error_statement(double voxel_size) {
  return voxels_and_model_units(thickness_error_bound(), voxel_size) +
         " against the mesh's wall thickness, away from convex edges and corners (where the largest ball containing "
         "a point is smaller by definition): the voxelization places each face anywhere within a voxel, and a wall N "
         "voxels thick reports N (even N) or N + 1 (odd N)";
}

}  // namespace voxd
