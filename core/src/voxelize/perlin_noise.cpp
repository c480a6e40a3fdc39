// Improved noise (Perlin 2002), following the reference implementation with
// the permutation shuffled from a seed. See perlin_noise.h.
#include "voxelize/perlin_noise.h"

#include <cmath>
#include <utility>

#include "voxelize/splitmix.h"

namespace voxd::detail {
namespace {

inline double fade(double t) { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); }
inline double lerp(double t, double a, double b) { return a + t * (b - a); }

// Dot product with one of the 12 edge directions of the cube (hash & 15).
inline double grad(int hash, double x, double y, double z) {
  const int h = hash & 15;
  const double u = h < 8 ? x : y;
  const double v = h < 4 ? y : (h == 12 || h == 14) ? x : z;
  return ((h & 1) == 0 ? u : -u) + ((h & 2) == 0 ? v : -v);
}

// floor(x) as the lattice cell (mod 256) and the offset in the cell. The
// integer path is exact and fast while |x| < 2^30; beyond, the table repeats
// every 256 cells anyway.
inline int cell(double x, double& offset) {
  if (std::abs(x) < 1073741824.0) {
    int i = static_cast<int>(x);
    if (x < static_cast<double>(i)) --i;
    offset = x - static_cast<double>(i);
    return i & 255;
  }
  const double f = std::floor(x);
  offset = x - f;
  return static_cast<int>(std::fmod(f, 256.0) + (f < 0 ? 256.0 : 0.0)) & 255;
}

}  // namespace

PerlinNoise::PerlinNoise(std::uint64_t seed) {
  std::array<std::uint8_t, 256> p;
  for (int i = 0; i < 256; ++i) p[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(i);
  std::uint64_t state = seed;
  for (std::uint64_t i = 255; i >= 1; --i) std::swap(p[i], p[splitmix64(state) % (i + 1)]);
  for (std::size_t i = 0; i < 512; ++i) p_[i] = p[i & 255];
}

double PerlinNoise::noise(double x, double y, double z) const {
  const int X = cell(x, x), Y = cell(y, y), Z = cell(z, z);
  const double u = fade(x), v = fade(y), w = fade(z);
  const auto P = [this](int i) { return static_cast<int>(p_[static_cast<std::size_t>(i)]); };
  const int A = P(X) + Y, AA = P(A) + Z, AB = P(A + 1) + Z;
  const int B = P(X + 1) + Y, BA = P(B) + Z, BB = P(B + 1) + Z;
  return lerp(w,
              lerp(v, lerp(u, grad(P(AA), x, y, z), grad(P(BA), x - 1, y, z)),
                   lerp(u, grad(P(AB), x, y - 1, z), grad(P(BB), x - 1, y - 1, z))),
              lerp(v, lerp(u, grad(P(AA + 1), x, y, z - 1), grad(P(BA + 1), x - 1, y, z - 1)),
                   lerp(u, grad(P(AB + 1), x, y - 1, z - 1), grad(P(BB + 1), x - 1, y - 1, z - 1))));
}

double PerlinNoise::turbulence(double x, double y, double z, int octaves) const {
  double sum = 0.0, f = 1.0;
  for (int k = 0; k < octaves; ++k, f *= 2.0) sum += std::abs(noise(x * f, y * f, z * f)) / f;
  return sum;
}

double PerlinNoise::fbm(double x, double y, double z, int octaves) const {
  double sum = 0.0, f = 1.0;
  for (int k = 0; k < octaves; ++k, f *= 2.0) sum += noise(x * f, y * f, z * f) / f;
  return sum;
}

}  // namespace voxd::detail
