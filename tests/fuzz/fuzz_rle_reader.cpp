// libFuzzer harness for the RLE reader, every value type: a lying header or
// runs past the grid must be an Error, never an allocation or a read past
// the input.
#include <algorithm>
#include <bit>
#include <cstdint>
#include <span>
#include <utility>

#include "voxd/error.h"
#include "voxd/encode/rle_slabs.h"
#include "voxd/encode/volume_format.h"

namespace {

// The bytes a few at a time, as a store's chunks arrive: the slab readers
// must see the same stream through their buffered window.
class Dribble final : public voxd::ByteSource {
 public:
  explicit Dribble(std::span<const std::uint8_t> data) : data_(data) {}
  std::size_t read(std::uint8_t* out, std::size_t size) override {
    const std::size_t n = std::min({size, data_.size() - at_, std::size_t{1} + (at_ * 7919) % 13});
    std::copy_n(data_.data() + at_, n, out);
    at_ += n;
    return n;
  }

 private:
  std::span<const std::uint8_t> data_;
  std::size_t at_ = 0;
};

// Runs a slab read; its outcome (a digest of the slabs, or the error's code).
template <class Read>
std::pair<std::uint64_t, int> outcome(const Read& read) {
  std::uint64_t digest = 0;
  try {
    read(digest);
    return {digest, -1};
  } catch (const voxd::Error& e) {
    return {digest, static_cast<int>(e.code())};
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::uint8_t> bytes(data, size);
  voxd::ReadLimits limits;
  limits.max_volume_bytes = std::uint64_t{64} << 20;
  try { (void)voxd::read_rle_bits(bytes, limits); } catch (const voxd::Error&) {}
  try { (void)voxd::read_rle_u8(bytes, limits); } catch (const voxd::Error&) {}
  try { (void)voxd::read_rle_u16(bytes, limits); } catch (const voxd::Error&) {}
  try { (void)voxd::read_rle_f32(bytes, limits); } catch (const voxd::Error&) {}
  try { (void)voxd::read_rle_rgba8(bytes, limits); } catch (const voxd::Error&) {}
  try { (void)voxd::read_rle_metadata(bytes); } catch (const voxd::Error&) {}
  // The slab readers, from memory and from a source that dribbles: the same
  // slabs, and the same error where the stream is bad.
  auto bits = [&](auto&& input) {
    return outcome([&](std::uint64_t& digest) {
      voxd::read_rle_bit_slabs(input, 3, [&](std::int64_t k0, const voxd::BitVolume& slab) {
        digest = digest * 31 + static_cast<std::uint64_t>(k0) * 7 + slab.count();
      }, limits);
    });
  };
  Dribble dribbled_bits(bytes);
  const auto from_bits = bits(bytes);
  if (from_bits != bits(dribbled_bits)) __builtin_trap();
  // The same stream read as runs: the same voxels layer by layer, or the
  // same error (each reader bounds its own memory, so a limit may differ).
  auto layers_of_bits = [&](auto&& input) {
    return outcome([&](std::uint64_t& digest) {
      voxd::read_rle_bit_slabs(input, 3, [&](std::int64_t k0, const voxd::BitVolume& slab) {
        for (std::int64_t k = 0; k < slab.grid().dims.z; ++k) {
          std::uint64_t n = 0;
          const std::uint64_t* layer = slab.slab(k);
          for (std::int64_t w = 0; w < slab.row_words() * slab.grid().dims.y; ++w)
            n += static_cast<std::uint64_t>(std::popcount(layer[w]));
          digest = digest * 31 + static_cast<std::uint64_t>(k0 + k) * 7 + n;
        }
      }, limits);
    });
  };
  auto layers_of_runs = [&](auto&& input, int threads) {
    return outcome([&](std::uint64_t& digest) {
      voxd::read_rle_run_slabs(input, 3, [&](std::int64_t k0, const voxd::RunSlab& slab) {
        for (std::int64_t k = 0; k < slab.grid().dims.z; ++k) {
          std::uint64_t n = 0;
          for (std::int64_t j = 0; j < slab.grid().dims.y; ++j) {
            const auto runs = slab.row(j, k);
            for (std::size_t r = 0; r < runs.size(); r += 2) {
              if (runs[r] >= runs[r + 1] || runs[r + 1] > slab.grid().dims.x || (r > 0 && runs[r] <= runs[r - 1]))
                __builtin_trap();  // runs in order, apart and in the row
              n += runs[r + 1] - runs[r];
            }
          }
          digest = digest * 31 + static_cast<std::uint64_t>(k0 + k) * 7 + n;
        }
      }, limits, threads);
    });
  };
  const auto layer_bits = layers_of_bits(bytes);
  Dribble dribbled_runs(bytes);
  const auto layer_runs = layers_of_runs(dribbled_runs, 1);
  // Decoded in batches on several threads: the same slabs up to the same
  // error, from memory and through the dribbling window.
  Dribble dribbled_batches(bytes);
  if (layers_of_runs(bytes, 3) != layer_runs || layers_of_runs(dribbled_batches, 3) != layer_runs) __builtin_trap();
  const int limit = static_cast<int>(voxd::ErrorCode::limit_exceeded);
  if (layer_bits.second != limit && layer_runs.second != limit) {
    if (layer_bits.second != layer_runs.second) __builtin_trap();
    if (layer_bits.second < 0 && layer_bits.first != layer_runs.first) __builtin_trap();
  }
  auto values = [&](auto&& input) {
    return outcome([&](std::uint64_t& digest) {
      voxd::read_rle_value_slabs(input, 2, [&](std::int64_t k0, const voxd::ValueVolume& slab) {
        digest = digest * 31 + static_cast<std::uint64_t>(k0) * 7 + static_cast<std::uint64_t>(voxd::grid_of(slab).dims.z);
      }, limits);
    });
  };
  Dribble dribbled_values(bytes);
  if (values(bytes) != values(dribbled_values)) __builtin_trap();
  return 0;
}
