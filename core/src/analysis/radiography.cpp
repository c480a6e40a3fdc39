// Thickness radiography on the bit-packed volume, 64 voxels per step.
//
// Rays along x lie inside one row: runs are found per word with count
// trailing zeros/ones. Rays along y and z cross rows, one bit per row; reading
// them bit by bit would cost a load per voxel. Instead 64 rows' words (64 ray
// positions x 64 neighbouring rays) are transposed as a 64x64 bit matrix, after
// which each word holds 64 consecutive voxels of one ray and the same per-word
// run scan applies. Blocks that are all empty or all full (most of a part's
// bounding box) skip the transpose.
#include "voxd/analysis/radiography.h"

#include <algorithm>
#include <array>
#include <bit>
#include <climits>
#include <stdexcept>
#include <string>

#include "encode/bit_transpose.h"
#include "run_rows.h"
#include "voxd/error.h"
#include "voxd/parallel.h"

namespace voxd {
namespace {

constexpr std::uint64_t kAllOnes = ~std::uint64_t{0};

// Accumulates the runs of one ray into its three pixels.
struct RayPixel {
  std::uint32_t* min;
  std::uint32_t* max;
  std::uint32_t* total;
  void add_run(std::uint32_t length) const {
    if (*min == 0 || length < *min) *min = length;
    if (length > *max) *max = length;
    *total += length;
  }
};

// Feeds 64 consecutive voxels of a ray (bit t = voxel t, LSB first) whose
// filled run so far (ending right before bit 0) is `open` voxels long. Every
// run that ends inside the word is reported; a run touching bit 63 stays open
// for the next word, so runs spanning words are measured whole.
inline void scan_word(std::uint64_t x, std::uint32_t& open, const RayPixel& px) {
  if (open != 0) {
    if (x == kAllOnes) {
      open += 64;
      return;
    }
    const int end = std::countr_one(x);  // < 64 here
    px.add_run(open + static_cast<std::uint32_t>(end));
    open = 0;
    x &= kAllOnes << end;
  }
  while (x != 0) {
    const int start = std::countr_zero(x);
    const std::uint64_t zeros_after = ~x & (kAllOnes << start);
    if (zeros_after == 0) {  // the run reaches bit 63: continues in the next word
      open = static_cast<std::uint32_t>(64 - start);
      return;
    }
    const int end = std::countr_zero(zeros_after);
    px.add_run(static_cast<std::uint32_t>(end - start));
    x &= kAllOnes << end;  // end < 64; bits below end are this run or zeros
  }
}

struct Maps {
  std::uint32_t* min;
  std::uint32_t* max;
  std::uint32_t* total;
  RayPixel at(std::size_t p) const { return {min + p, max + p, total + p}; }
  // The maps from pixel p on (a slab's first image row).
  Maps from(std::size_t p) const { return {min + p, max + p, total + p}; }
};

Maps maps_of(ThicknessImage& image) { return {image.min.data(), image.max.data(), image.total.data()}; }

// Rays along x: image row k, column j.
void rays_along_x(const BitVolume& v, const Maps& maps, int threads) {
  const glm::i64vec3 d = v.grid().dims;
  const std::int64_t words = v.row_words();
  parallel_for(0, d.z, 4, threads, [&](std::int64_t k0, std::int64_t k1) {
    for (std::int64_t k = k0; k < k1; ++k) {
      for (std::int64_t j = 0; j < d.y; ++j) {
        const std::uint64_t* row = v.row(j, k);
        const RayPixel px = maps.at(static_cast<std::size_t>(k * d.y + j));
        std::uint32_t open = 0;
        for (std::int64_t w = 0; w < words; ++w) scan_word(row[w], open, px);
        if (open != 0) px.add_run(open);  // bits past dims.x are zero, but a full last word leaves one open
      }
    }
  });
}

// Rays across rows: the rays of one image row are the dims.x voxels of word
// row `base`, and ray position p is at base + p * stride (stride = one row for
// y, one slab for z). `open` is scratch of dims.x entries.
void scan_strided_rays(const std::uint64_t* base, std::int64_t stride, std::int64_t length, std::int64_t nx,
                       std::int64_t words, const Maps& maps, std::size_t pixel0, std::vector<std::uint32_t>& open) {
  std::fill(open.begin(), open.end(), 0u);
  alignas(64) std::array<std::uint64_t, 64> block;
  for (std::int64_t p0 = 0; p0 < length; p0 += 64) {
    const int m = static_cast<int>(std::min<std::int64_t>(64, length - p0));
    const std::uint64_t* first = base + p0 * stride;
    for (std::int64_t w = 0; w < words; ++w) {
      std::uint64_t any = 0;
      std::uint64_t all = kAllOnes;
      for (int t = 0; t < m; ++t) {
        const std::uint64_t x = first[t * stride + w];
        block[static_cast<std::size_t>(t)] = x;
        any |= x;
        all &= x;
      }
      const int lanes = static_cast<int>(std::min<std::int64_t>(64, nx - w * 64));
      std::uint32_t* lane_open = open.data() + w * 64;
      const std::size_t lane_pixel = pixel0 + static_cast<std::size_t>(w * 64);
      if (any == 0) {  // empty block: only runs left open from the last block end here
        for (int c = 0; c < lanes; ++c) {
          if (lane_open[c] != 0) {
            maps.at(lane_pixel + static_cast<std::size_t>(c)).add_run(lane_open[c]);
            lane_open[c] = 0;
          }
        }
        continue;
      }
      if (m == 64 && all == kAllOnes) {  // full block (implies 64 lanes): every run grows by 64
        for (int c = 0; c < 64; ++c) lane_open[c] += 64;
        continue;
      }
      for (int t = m; t < 64; ++t) block[static_cast<std::size_t>(t)] = 0;  // past the ray end: empty
      encode::transpose_64x64(block.data());  // block[c] bit t = ray c at position p0 + t
      for (int c = 0; c < lanes; ++c) {
        const std::uint64_t x = block[static_cast<std::size_t>(c)];
        if (x == 0 && lane_open[c] == 0) continue;
        scan_word(x, lane_open[c], maps.at(lane_pixel + static_cast<std::size_t>(c)));
      }
    }
  }
  for (std::int64_t i = 0; i < nx; ++i) {
    if (open[static_cast<std::size_t>(i)] != 0) maps.at(pixel0 + static_cast<std::size_t>(i)).add_run(open[static_cast<std::size_t>(i)]);
  }
}

// Rays along y (image row k, column i) or z (image row j, column i).
void rays_across_rows(const BitVolume& v, int axis, const Maps& maps, int threads) {
  const glm::i64vec3 d = v.grid().dims;
  const std::int64_t rows = axis == 1 ? d.z : d.y;
  const std::int64_t length = axis == 1 ? d.y : d.z;
  const std::int64_t stride = axis == 1 ? v.row_words() : static_cast<std::int64_t>(v.slab_words());
  parallel_for(0, rows, 1, threads, [&](std::int64_t r0, std::int64_t r1) {
    std::vector<std::uint32_t> open(static_cast<std::size_t>(v.row_words() * 64));
    for (std::int64_t r = r0; r < r1; ++r) {
      const std::uint64_t* base = axis == 1 ? v.row(0, r) : v.row(r, 0);
      scan_strided_rays(base, stride, length, d.x, v.row_words(), maps, static_cast<std::size_t>(r * d.x), open);
    }
  });
}

}  // namespace

ImageSize projected_size(const Grid& grid, int axis) {
  if (axis < 0 || axis > 2) {
    throw Error(ErrorCode::invalid_argument, "axis must be 0 (x), 1 (y) or 2 (z), got " + std::to_string(axis));
  }
  const std::int64_t w = axis == 0 ? grid.dims.y : grid.dims.x;
  const std::int64_t h = axis == 2 ? grid.dims.y : grid.dims.z;
  // Pixels are indexed with int in image code and PNG rows: keep the product in range.
  if (w < 0 || h < 0 || w > INT_MAX || h > INT_MAX || (w != 0 && h > INT_MAX / w)) {
    throw Error(ErrorCode::limit_exceeded, "projected image of " + std::to_string(w) + " x " + std::to_string(h) +
                                               " pixels is too large (at most " + std::to_string(INT_MAX) + " pixels)");
  }
  return {static_cast<int>(w), static_cast<int>(h)};
}

namespace {

// All three maps zero, sized for the projection of `grid` along `axis`.
ThicknessImage blank_image(const Grid& grid, int axis) {
  const ImageSize size = projected_size(grid, axis);
  ThicknessImage image;
  image.width = size.width;
  image.height = size.height;
  const std::size_t pixels = static_cast<std::size_t>(size.width) * static_cast<std::size_t>(size.height);
  for (UnclearedVector<std::uint32_t>* map : {&image.min, &image.max, &image.total}) assign_on_every_thread(*map, pixels, 0u);
  return image;
}

}  // namespace

void free_on_every_thread(ThicknessImage& image, int threads) {
  for (UnclearedVector<std::uint32_t>* map : {&image.min, &image.max, &image.total}) free_on_every_thread(*map, threads);
}

ThicknessImage radiography(const BitVolume& volume, int axis, int threads) {
  ThicknessImage image = blank_image(volume.grid(), axis);
  if (image.min.empty() || volume.grid().voxel_count() == 0) return image;
  const Maps maps = maps_of(image);
  if (axis == 0) {
    rays_along_x(volume, maps, threads);
  } else {
    rays_across_rows(volume, axis, maps, threads);
  }
  return image;
}

RadiographyAccumulator::RadiographyAccumulator(const Grid& grid, int axis)
    : grid_(grid), axis_(axis), image_(blank_image(grid, axis)) {
  if (axis == 2) {
    assign_on_every_thread(run_start_, image_.min.size(), 0u);
    last_layer_.assign(static_cast<std::size_t>((grid.dims.x + 63) / 64 * grid.dims.y), 0);
  }
}

void RadiographyAccumulator::check_slab(std::int64_t k0, Kind slab) {
  if (k0 != next_k_) throw std::logic_error("RadiographyAccumulator: slab at layer " + std::to_string(k0) +
                                            " where layer " + std::to_string(next_k_) + " was expected");
  if (kind_ != Kind::none && kind_ != slab)
    throw std::logic_error("RadiographyAccumulator: takes all its slabs as bits or all as runs");
  kind_ = slab;
}

void RadiographyAccumulator::add(std::int64_t k0, const RunSlab& slab, int threads) {
  check_slab(k0, Kind::runs);
  threads_ = threads;
  const glm::i64vec3 d = slab.grid().dims;
  next_k_ += d.z;
  if (d.z == 0 || image_.min.empty()) return;
  const Maps maps = maps_of(image_);
  using detail::for_each_difference;
  if (axis_ == 0) {  // a ray is a row: its runs are the row's
    parallel_for(0, d.z, 4, threads, [&](std::int64_t a, std::int64_t b) {
      for (std::int64_t kk = a; kk < b; ++kk)
        for (std::int64_t j = 0; j < d.y; ++j) {
          const detail::Runs row = slab.row(j, kk);
          const RayPixel px = maps.at(static_cast<std::size_t>((k0 + kk) * d.y + j));
          for (std::size_t r = 0; r < row.size(); r += 2) px.add_run(row[r + 1] - row[r]);
        }
    });
    return;
  }
  if (axis_ == 1) {  // a layer's rays cross its rows: runs begin and end where rows differ
    parallel_for(0, d.z, 1, threads, [&](std::int64_t a, std::int64_t b) {
      std::vector<std::uint32_t> start(static_cast<std::size_t>(d.x));
      for (std::int64_t kk = a; kk < b; ++kk) {
        const Maps layer = maps.from(static_cast<std::size_t>((k0 + kk) * d.x));
        detail::Runs before;
        for (std::int64_t j = 0; j <= d.y; ++j) {
          const detail::Runs row = j < d.y ? slab.row(j, kk) : detail::Runs{};
          const auto at = static_cast<std::uint32_t>(j);
          for_each_difference(row, before, [&](std::uint32_t b0, std::uint32_t e0) {
            std::fill(start.begin() + b0, start.begin() + e0, at);
          });
          for_each_difference(before, row, [&](std::uint32_t b0, std::uint32_t e0) {
            for (std::uint32_t i = b0; i < e0; ++i) layer.at(i).add_run(at - start[i]);
          });
          before = row;
        }
      }
    });
    return;
  }
  // Along z the rows differ from the layer before's, the first from the
  // last slab's last layer.
  parallel_for(0, d.y, 16, threads, [&](std::int64_t j0, std::int64_t j1) {
    for (std::int64_t j = j0; j < j1; ++j) {
      const std::size_t pixel0 = static_cast<std::size_t>(j * d.x);
      for (std::int64_t kk = 0; kk < d.z; ++kk) {
        const auto k = static_cast<std::uint32_t>(k0 + kk);
        const detail::Runs row = slab.row(j, kk);
        const detail::Runs before = kk > 0 ? slab.row(j, kk - 1) : k0 > 0 ? last_runs_.row(j, 0) : detail::Runs{};
        for_each_difference(row, before, [&](std::uint32_t b0, std::uint32_t e0) {
          std::fill(run_start_.begin() + static_cast<std::ptrdiff_t>(pixel0 + b0),
                    run_start_.begin() + static_cast<std::ptrdiff_t>(pixel0 + e0), k);
        });
        for_each_difference(before, row, [&](std::uint32_t b0, std::uint32_t e0) {
          for (std::uint32_t i = b0; i < e0; ++i) maps.at(pixel0 + i).add_run(k - run_start_[pixel0 + i]);
        });
      }
    }
  });
  last_runs_ = detail::last_layers(last_runs_, slab, 1);
}

void RadiographyAccumulator::add(std::int64_t k0, const BitVolume& slab, int threads) {
  check_slab(k0, Kind::bits);
  threads_ = threads;
  const glm::i64vec3 d = slab.grid().dims;
  next_k_ += d.z;
  if (d.z == 0 || image_.min.empty()) return;
  const Maps maps = maps_of(image_);
  // Along x and y image row k is layer k: this slab's rows start k0 rows down.
  if (axis_ == 0) return rays_along_x(slab, maps.from(static_cast<std::size_t>(k0 * d.y)), threads);
  if (axis_ == 1) return rays_across_rows(slab, 1, maps.from(static_cast<std::size_t>(k0 * d.x)), threads);
  // Along z a run begins where a voxel is filled and the one below was not,
  // and ends where it is empty and the one below was filled: only those
  // transitions cost work, one word of 64 rays at a time.
  const std::int64_t words = slab.row_words();
  parallel_for(0, d.y, 16, threads, [&](std::int64_t j0, std::int64_t j1) {
    for (std::int64_t kk = 0; kk < d.z; ++kk) {
      const auto k = static_cast<std::uint32_t>(k0 + kk);
      for (std::int64_t j = j0; j < j1; ++j) {
        const std::uint64_t* row = slab.row(j, kk);
        std::uint64_t* below = last_layer_.data() + j * words;
        for (std::int64_t w = 0; w < words; ++w) {
          const std::uint64_t now = row[w], before = below[w];
          if (now == before) continue;
          const std::size_t pixel0 = static_cast<std::size_t>(j * d.x + w * 64);
          for (std::uint64_t begins = now & ~before; begins; begins &= begins - 1)
            run_start_[pixel0 + static_cast<std::size_t>(std::countr_zero(begins))] = k;
          for (std::uint64_t ends = before & ~now; ends; ends &= ends - 1) {
            const std::size_t p = pixel0 + static_cast<std::size_t>(std::countr_zero(ends));
            maps.at(p).add_run(k - run_start_[p]);
          }
          below[w] = now;
        }
      }
    }
  });
}

ThicknessImage RadiographyAccumulator::take() {
  if (next_k_ != grid_.dims.z)
    throw std::logic_error("RadiographyAccumulator: " + std::to_string(next_k_) + " of " +
                           std::to_string(grid_.dims.z) + " layers were added");
  if (axis_ == 2 && !image_.min.empty() && kind_ == Kind::runs && grid_.dims.z > 0) {
    const Maps maps = maps_of(image_);
    const auto top = static_cast<std::uint32_t>(grid_.dims.z);
    for (std::int64_t j = 0; j < grid_.dims.y; ++j) {
      const detail::Runs open = last_runs_.row(j, 0);
      for (std::size_t r = 0; r < open.size(); r += 2)
        for (std::uint32_t i = open[r]; i < open[r + 1]; ++i) {
          const std::size_t p = static_cast<std::size_t>(j * grid_.dims.x) + i;
          maps.at(p).add_run(top - run_start_[p]);
        }
    }
  } else if (axis_ == 2 && !image_.min.empty()) {  // runs still open reach the top of the grid
    const Maps maps = maps_of(image_);
    const std::int64_t words = (grid_.dims.x + 63) / 64;
    const auto top = static_cast<std::uint32_t>(grid_.dims.z);
    for (std::int64_t j = 0; j < grid_.dims.y; ++j)
      for (std::int64_t w = 0; w < words; ++w)
        for (std::uint64_t open = last_layer_[static_cast<std::size_t>(j * words + w)]; open; open &= open - 1) {
          const std::size_t p = static_cast<std::size_t>(j * grid_.dims.x + w * 64 + std::countr_zero(open));
          maps.at(p).add_run(top - run_start_[p]);
        }
  }
  free_on_every_thread(run_start_, threads_);
  last_layer_ = {};
  last_runs_ = {};
  return std::move(image_);
}

ThicknessStats thickness_stats(std::span<const std::uint32_t> values, int bins) {
  if (bins < 1) throw Error(ErrorCode::invalid_argument, "histogram bins must be at least 1, got " + std::to_string(bins));
  ThicknessStats s;
  std::vector<std::uint32_t> hits;
  hits.reserve(values.size());
  std::uint64_t sum = 0;
  for (const std::uint32_t v : values) {
    if (v == 0) continue;
    hits.push_back(v);
    sum += v;
  }
  if (hits.empty()) return s;
  const auto [lo, hi] = std::minmax_element(hits.begin(), hits.end());
  s.rays = hits.size();
  s.min = *lo;
  s.max = *hi;
  s.mean = static_cast<double>(sum) / static_cast<double>(s.rays);
  const std::uint64_t span = std::uint64_t{s.max} - s.min + 1;
  s.bin_width = static_cast<double>(span) / bins;
  s.histogram.assign(static_cast<std::size_t>(bins), 0);
  for (const std::uint32_t v : hits) ++s.histogram[static_cast<std::size_t>((std::uint64_t{v} - s.min) * static_cast<std::uint64_t>(bins) / span)];
  // Nearest rank: rank ceil(p * n / 100), 1-based. Ascending p, so each
  // nth_element only reorders the part right of the previous one.
  auto rank_value = [&](std::uint64_t p, std::size_t from) {
    const std::size_t rank = static_cast<std::size_t>(std::max<std::uint64_t>(1, (p * s.rays + 99) / 100));
    const auto nth = hits.begin() + static_cast<std::ptrdiff_t>(rank - 1);
    std::nth_element(hits.begin() + static_cast<std::ptrdiff_t>(from), nth, hits.end());
    return std::pair{*nth, rank - 1};
  };
  const auto [p5, i5] = rank_value(5, 0);
  const auto [p50, i50] = rank_value(50, i5);
  const auto [p95, i95] = rank_value(95, i50);
  s.p5 = p5;
  s.p50 = p50;
  s.p95 = p95;
  (void)i95;
  return s;
}

}  // namespace voxd
