#pragma once
// Ken Perlin's improved noise (2002) in 3D with a seeded permutation table,
// and its turbulence and fractal (fBm) sums. Formulas in voxd/voxelize/slice_functions.h.
#include <array>
#include <cstdint>

namespace voxd::detail {

class PerlinNoise {
 public:
  // The permutation 0..255 shuffled by Fisher-Yates with splitmix64(seed).
  explicit PerlinNoise(std::uint64_t seed);

  // N(x, y, z), continuous, roughly in [-1, 1], 0 at lattice points.
  double noise(double x, double y, double z) const;
  // T = sum_{k<octaves} |N(2^k q)| / 2^k.
  double turbulence(double x, double y, double z, int octaves) const;
  // F = sum_{k<octaves} N(2^k q) / 2^k.
  double fbm(double x, double y, double z, int octaves) const;

  const std::array<std::uint8_t, 512>& permutation() const { return p_; }

 private:
  std::array<std::uint8_t, 512> p_{};  // the permutation twice, so p[i + 1] never wraps
};

}  // namespace voxd::detail
