#include "voxd/analysis/cleanup.h"

#include <atomic>
#include <bit>
#include <vector>

#include "voxd/parallel.h"

namespace voxd {

CleanupReport clean_up(BitVolume& volume, const CleanupOptions& options, int threads) {
  const Grid& g = volume.grid();
  const std::int64_t words = volume.row_words();
  const std::uint64_t zero_row_word = 0;
  std::atomic<std::uint64_t> isolated{0}, lines{0}, sheets{0};
  // Removal masks are computed from the input into a separate list of slabs,
  // then applied, so the pass is simultaneous.
  std::vector<std::vector<std::uint64_t>> remove(static_cast<std::size_t>(g.dims.z));
  const std::size_t slab_words = volume.slab_words();
  const BitVolume& in = volume;
  auto word_at = [&](std::int64_t j, std::int64_t k, std::int64_t w) -> std::uint64_t {
    if (j < 0 || k < 0 || j >= g.dims.y || k >= g.dims.z) return zero_row_word;
    return in.row(j, k)[w];
  };
  parallel_for(0, g.dims.z, 1, threads, [&](std::int64_t k0, std::int64_t k1) {
    std::uint64_t n_iso = 0, n_line = 0, n_sheet = 0;
    for (std::int64_t k = k0; k < k1; ++k) {
      std::vector<std::uint64_t> mask;
      for (std::int64_t j = 0; j < g.dims.y; ++j) {
        const std::uint64_t* row = in.row(j, k);
        for (std::int64_t w = 0; w < words; ++w) {
          const std::uint64_t c = row[w];
          if (!c) continue;
          // Neighbour at i-1 and i+1 for each bit, across word boundaries.
          const std::uint64_t left = (c << 1) | (w > 0 ? row[w - 1] >> 63 : 0);
          const std::uint64_t right = (c >> 1) | (w + 1 < words ? row[w + 1] << 63 : 0);
          const std::uint64_t tx = ~left & ~right;
          const std::uint64_t ty = ~word_at(j - 1, k, w) & ~word_at(j + 1, k, w);
          const std::uint64_t tz = ~word_at(j, k - 1, w) & ~word_at(j, k + 1, w);
          const std::uint64_t t3 = tx & ty & tz;
          const std::uint64_t t2 = ((tx & ty) | (ty & tz) | (tx & tz)) & ~t3;
          const std::uint64_t t1 = (tx | ty | tz) & ~(tx & ty) & ~(ty & tz) & ~(tx & tz);
          std::uint64_t r = 0;
          if (options.isolated) r |= c & t3;
          if (options.lines) r |= c & t2;
          if (options.sheets) r |= c & t1;
          if (!r) continue;
          if (mask.empty()) mask.assign(slab_words, 0);
          mask[static_cast<std::size_t>(j * words + w)] = r;
          n_iso += static_cast<std::uint64_t>(std::popcount(r & t3));
          n_line += static_cast<std::uint64_t>(std::popcount(r & t2));
          n_sheet += static_cast<std::uint64_t>(std::popcount(r & t1));
        }
      }
      remove[static_cast<std::size_t>(k)] = std::move(mask);
    }
    isolated += n_iso;
    lines += n_line;
    sheets += n_sheet;
  });
  for (std::int64_t k = 0; k < g.dims.z; ++k) {
    const auto& mask = remove[static_cast<std::size_t>(k)];
    if (mask.empty()) continue;
    std::uint64_t* slab = volume.slab(k);
    for (std::size_t i = 0; i < slab_words; ++i) slab[i] &= ~mask[i];
  }
  return {isolated.load(), lines.load(), sheets.load()};
}

}  // namespace voxd
