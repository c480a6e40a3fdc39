#pragma once
// __int128 to double, rounded to nearest with ties to even, for the CPU and
// the CUDA kernels alike (ray_triangle.h, column_scan.h). GCC casts a
// 128-bit integer with a call to libgcc's __floattidf: the parity scan
// converter made 74 million of them for one solid at 8192^3, 3.4% of its
// instructions. Tested against GCC's cast in coverage_device_test.cpp.
#include <math.h>

#include <cstdint>

#include "voxelize/host_device.h"

namespace voxd::detail {

// Leading zero bits of a non-zero 64-bit word.
VOXD_HD inline int leading_zeros(std::uint64_t x) {
#if defined(__CUDA_ARCH__)
  return __clzll(static_cast<long long>(x));
#else
  return __builtin_clzll(x);
#endif
}

// v rounded to the nearest double, ties to even: what GCC's conversion does
// on the CPU, written out so that the GPU does not depend on how its
// compiler converts a 128-bit integer.
VOXD_HD inline double int128_to_double(__int128 v) {
  // A 64-bit integer converts in one instruction, rounded the same way
  // (cvtsi2sd on the CPU, cvt.rn.f64.s64 on the GPU).
  const auto narrow = static_cast<std::int64_t>(v);
  if (narrow == v) return static_cast<double>(narrow);
  const bool negative = v < 0;
  const unsigned __int128 m = negative ? -static_cast<unsigned __int128>(v) : static_cast<unsigned __int128>(v);
  const auto hi = static_cast<std::uint64_t>(m >> 64);
  const int length = hi != 0 ? 128 - leading_zeros(hi) : 64 - leading_zeros(static_cast<std::uint64_t>(m));
  const int shift = length - 53;  // >= 1: |v| >= 2^63
  auto mantissa = static_cast<std::uint64_t>(m >> shift);
  const unsigned __int128 rest = m & ((static_cast<unsigned __int128>(1) << shift) - 1);
  const unsigned __int128 half = static_cast<unsigned __int128>(1) << (shift - 1);
  if (rest > half || (rest == half && (mantissa & 1) != 0)) ++mantissa;  // 2^53 is still exact
  const double magnitude = ldexp(static_cast<double>(mantissa), shift);
  return negative ? -magnitude : magnitude;
}

}  // namespace voxd::detail
