#include "voxelize/parity_voxelizer.h"

#include <algorithm>
#include <atomic>
#include <climits>
#include <stdexcept>
#include <cstdint>
#include <vector>

#include "voxd/parallel.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd::detail {
namespace {

ScanAxes axes_for_ray(int ray) {
  // The partition (row) axis is never x, so chunks own whole 64-bit words.
  switch (ray) {
    case 0: return {0, 1, 2};
    case 1: return {1, 0, 2};
    default: return {2, 0, 1};
  }
}

// In-place inclusive prefix XOR of words [first, last] of a row (the words
// holding toggles): bit i becomes the XOR of bits 0..i, turning crossing
// toggles into filled runs. Words before `first` hold no toggle and stay
// zero; words after `last` take the final state (ones only when the row ends
// inside the mesh, e.g. a grid that cuts it). Untouched words, and the memory
// pages under them, are never written.
inline void prefix_xor_row(std::uint64_t* row, std::int64_t first, std::int64_t last, std::int64_t words,
                           std::uint64_t last_word_mask) {
  std::uint64_t carry = 0;
  for (std::int64_t w = first; w <= last; ++w) {
    std::uint64_t x = row[w];
    if (x == 0) {  // no crossing in this word: inside or outside throughout
      row[w] = carry;
      continue;
    }
    x ^= x << 1;
    x ^= x << 2;
    x ^= x << 4;
    x ^= x << 8;
    x ^= x << 16;
    x ^= x << 32;
    x ^= carry;
    carry = std::uint64_t{0} - (x >> 63);
    row[w] = x;
  }
  if (carry != 0) {
    for (std::int64_t w = last + 1; w < words; ++w) row[w] = carry;
  }
  if (carry != 0 || last == words - 1) row[words - 1] &= last_word_mask;  // bits past dims.x stay zero
}

// A job this small takes about a millisecond on one core: starting threads
// costs a noticeable part of that, and in the service other jobs keep the
// other cores busy, so it runs on the calling thread.
bool small_job(const Mesh& mesh, const Grid& grid) {
  return grid.voxel_count() <= (std::uint64_t{1} << 21) && mesh.triangles.size() <= (std::size_t{1} << 16);
}

}  // namespace

ParityVoxelizer::ParityVoxelizer(const Mesh& mesh, const Grid& grid, int ray_axis, int threads, std::int64_t rows_per_chunk)
    : grid_(grid),
      axes_(axes_for_ray(ray_axis)),
      threads_(small_job(mesh, grid) ? 1 : threads > 0 ? threads : default_thread_count()),
      fixed_(mesh, grid) {
  const std::int64_t rows = grid.dims[axes_.v];
  // Enough chunks to balance threads, few enough that triangles rarely straddle.
  const std::int64_t per_chunk =
      rows_per_chunk > 0 ? rows_per_chunk : std::clamp<std::int64_t>(rows / (8 * threads_), 1, 16);
  bins_ = bin_triangles(fixed_, axes_.v, rows, per_chunk, 0, threads_);
}

template <class Emit>
void ParityVoxelizer::for_each_crossing(std::int64_t chunk, Emit&& emit) const {
  const std::int64_t row0 = chunk * bins_.rows_per_chunk;
  const std::int64_t row1 = std::min(row0 + bins_.rows_per_chunk, grid_.dims[axes_.v]);
  const std::int64_t columns_u = grid_.dims[axes_.u];
  const auto& tris = fixed_.triangles();
  const std::uint32_t begin = bins_.offsets[chunk], end = bins_.offsets[chunk + 1];
  // A chunk's triangles lie all over the mesh, and most take less work than
  // a cache miss: the loop waits on memory unless the triangles a few
  // ahead, and then their corners, are fetched early.
  constexpr std::uint32_t kTriangleAhead = 16, kCornerAhead = 8;
  for (std::uint32_t n = begin; n < end; ++n) {
    if (n + kTriangleAhead < end) __builtin_prefetch(&tris[bins_.triangles[n + kTriangleAhead]]);
    if (n + kCornerAhead < end) {
      const auto& ahead = tris[bins_.triangles[n + kCornerAhead]];
      for (int c = 0; c < 3; ++c) __builtin_prefetch(fixed_.corner_address(ahead[c]));
    }
    const auto& t = tris[bins_.triangles[n]];
    scan_triangle(fixed_.vertex(t[0]), fixed_.vertex(t[1]), fixed_.vertex(t[2]), axes_, row0, row1, columns_u, emit);
  }
}

void ParityVoxelizer::chunk_crossings(std::int64_t chunk, std::vector<RowCrossing>& out) const {
  if (axes_.ray != 0) throw std::logic_error("crossings by row need rays along x");
  const std::int64_t row0 = chunk * bins_.rows_per_chunk, ny = grid_.dims.y, nx = grid_.dims.x;
  for_each_crossing(chunk, [&](std::int64_t j, std::int64_t k, std::int64_t c) {
    if (c >= nx) return;  // past the grid: affects nothing
    out.push_back({static_cast<std::uint32_t>((k - row0) * ny + j), static_cast<std::uint32_t>(std::max<std::int64_t>(c, 0))});
  });
}

void ParityVoxelizer::fill_chunk(std::int64_t chunk, BitVolume& volume, std::int64_t z_origin) const {
  if (z_origin != 0 && axes_.ray == 2) throw std::logic_error("rays along z need the whole grid's z layers");
  const std::int64_t row0 = chunk * bins_.rows_per_chunk;
  const std::int64_t row1 = std::min(row0 + bins_.rows_per_chunk, grid_.dims[axes_.v]);
  const std::int64_t nx = grid_.dims.x, ny = grid_.dims.y, nz = grid_.dims.z;
  const std::int64_t rw = volume.row_words();
  const std::int64_t ray_len = grid_.dims[axes_.ray];
  std::uint64_t* words = volume.data();

  auto toggle = [words](std::int64_t word, std::int64_t bit) { words[word] ^= std::uint64_t{1} << bit; };
  auto for_each_triangle = [&](auto&& emit) { for_each_crossing(chunk, emit); };
  // A crossing before the grid toggles voxel 0; one past it affects nothing.
  // Rays along x also record each row's first and last toggled word, so the
  // prefix pass below touches only the words between them.
  std::vector<std::uint32_t> first_word, last_word;
  if (axes_.ray == 0) {
    first_word.assign(static_cast<std::size_t>((row1 - row0) * ny), UINT32_MAX);
    last_word.assign(first_word.size(), 0);
  }
  switch (axes_.ray) {
    case 0:
      for_each_triangle([&](std::int64_t j, std::int64_t k, std::int64_t c) {
        if (c >= ray_len) return;
        c = std::max<std::int64_t>(c, 0);
        toggle(((k - z_origin) * ny + j) * rw + (c >> 6), c & 63);
        const auto r = static_cast<std::size_t>((k - row0) * ny + j);
        const auto w = static_cast<std::uint32_t>(c >> 6);
        first_word[r] = std::min(first_word[r], w);
        last_word[r] = std::max(last_word[r], w);
      });
      break;
    case 1:
      for_each_triangle([&](std::int64_t i, std::int64_t k, std::int64_t c) {
        if (c >= ray_len) return;
        c = std::max<std::int64_t>(c, 0);
        toggle(((k - z_origin) * ny + c) * rw + (i >> 6), i & 63);
      });
      break;
    default:
      for_each_triangle([&](std::int64_t i, std::int64_t j, std::int64_t c) {
        if (c >= ray_len) return;
        c = std::max<std::int64_t>(c, 0);
        toggle((c * ny + j) * rw + (i >> 6), i & 63);
      });
      break;
  }

  // Prefix XOR along the ray turns toggles into runs.
  switch (axes_.ray) {
    case 0: {
      const std::uint64_t mask = (nx & 63) ? (std::uint64_t{1} << (nx & 63)) - 1 : ~std::uint64_t{0};
      for (std::int64_t k = row0; k < row1; ++k)
        for (std::int64_t j = 0; j < ny; ++j) {
          const auto r = static_cast<std::size_t>((k - row0) * ny + j);
          if (first_word[r] <= last_word[r])
            prefix_xor_row(volume.row(j, k - z_origin), first_word[r], last_word[r], rw, mask);
        }
      break;
    }
    case 1:
      for (std::int64_t k = row0; k < row1; ++k)
        for (std::int64_t j = 1; j < ny; ++j) {
          std::uint64_t* cur = volume.row(j, k - z_origin);
          const std::uint64_t* prev = volume.row(j - 1, k - z_origin);
          for (std::int64_t w = 0; w < rw; ++w) cur[w] ^= prev[w];
        }
      break;
    default:
      for (std::int64_t k = 1; k < nz; ++k)
        for (std::int64_t j = row0; j < row1; ++j) {
          std::uint64_t* cur = volume.row(j, k);
          const std::uint64_t* prev = volume.row(j, k - 1);
          for (std::int64_t w = 0; w < rw; ++w) cur[w] ^= prev[w];
        }
      break;
  }
}

void ParityVoxelizer::fill(BitVolume& volume, JobControl* control, double progress_from, double progress_to) const {
  std::atomic<std::int64_t> done{0};
  const std::int64_t total = chunk_count();
  parallel_for(0, total, 1, threads_, [&](std::int64_t c0, std::int64_t c1) {
    for (std::int64_t c = c0; c < c1; ++c) {
      if (control) control->check_cancelled();
      fill_chunk(c, volume);
      const std::int64_t d = done.fetch_add(1) + 1;
      if (control)
        control->set_progress(progress_from + (progress_to - progress_from) * static_cast<double>(d) /
                                                  static_cast<double>(total));
    }
  });
}

}  // namespace voxd::detail

namespace voxd {

BitVolume voxelize_parity(const Mesh& mesh, const Grid& grid, int axis, int threads, JobControl* control) {
  BitVolume volume(grid);
  detail::ParityVoxelizer(mesh, grid, axis, threads).fill(volume, control);
  return volume;
}

}  // namespace voxd
