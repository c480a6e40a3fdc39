#pragma once
// The lower envelope of the parabolas (u - i)^2 + g[i] over the sites i of
// one line (Meijster, Roerdink & Hesselink 2000, phase 2), in integers with
// floor division, so exact. The distance transform (which wants the
// envelope's value at every u) and the feature transform (which wants the
// winning site) both solve their passes with it.
#include <cmath>
#include <cstdint>

namespace voxd::detail {

// floor(a / b) for b > 0 (C++ division truncates towards zero). Below
// 2^52 in magnitude, by dividing doubles: both are exact, the quotient is
// within 2^-53 |a| / b of a / b (relative rounding), and a / b is either
// an integer (then exact) or at least 1 / b from one, which that error
// never reaches, so the floor is the same. A 64-bit integer division is
// several times slower, and the passes of the transforms make one for
// every voxel.
inline std::int64_t floor_div(std::int64_t a, std::int64_t b) {
  constexpr std::int64_t kExact = std::int64_t{1} << 52;
  if (a > -kExact && a < kExact && b < kExact)
    return static_cast<std::int64_t>(std::floor(static_cast<double>(a) / static_cast<double>(b)));
  const std::int64_t q = a / b;
  return (a % b != 0 && a < 0) ? q - 1 : q;
}

// Calls won(u, i) for every u in [0, m), from m - 1 down to 0, with the
// site i whose parabola is lowest at u. Scratch s and t hold m entries.
// With kSomeFar, an entry with g[i] >= far is no site and is left out, and
// won(u, -1) is called for every u when no entry is a site.
template <bool kSomeFar, typename G, typename Won>
void lower_envelope(const G* g, int m, int* s, int* t, std::int64_t far, Won&& won) {
  auto f = [g](std::int64_t x, std::int64_t i) { return (x - i) * (x - i) + static_cast<std::int64_t>(g[i]); };
  auto sep = [g](std::int64_t i, std::int64_t u) {
    return floor_div(u * u - i * i + static_cast<std::int64_t>(g[u]) - static_cast<std::int64_t>(g[i]), 2 * (u - i));
  };
  int q = -1;
  for (int u = 0; u < m; ++u) {
    if constexpr (kSomeFar) {
      if (static_cast<std::int64_t>(g[u]) >= far) continue;
    }
    while (q >= 0 && f(t[q], s[q]) > f(t[q], u)) --q;
    if (q < 0) {
      q = 0;
      s[0] = u;
      t[0] = 0;
    } else {
      const std::int64_t w = 1 + sep(s[q], u);
      if (w < m) {
        ++q;
        s[q] = u;
        t[q] = static_cast<int>(w);
      }
    }
  }
  if (kSomeFar && q < 0) {
    for (int u = m - 1; u >= 0; --u) won(u, -1);
    return;
  }
  for (int u = m - 1; u >= 0; --u) {
    won(u, s[q]);
    if (u == t[q]) --q;
  }
}

// The same envelope over a line holding only the sites k < count, at
// ascending positions pos[k] in [0, m) with g[k] (none of them far): the
// same comparisons on the same numbers, so the same winners, in time for
// the sites and the positions asked for rather than the whole line. Calls
// won(u, k) for every u in [from, to), from to - 1 down, with the site k
// lowest at u; nothing when count is 0. Scratch s and t hold count entries.
template <typename Won>
void lower_envelope_of_sites(const std::int64_t* pos, const std::int64_t* g, int count, std::int64_t m, int* s,
                             std::int64_t* t, std::int64_t from, std::int64_t to, Won&& won) {
  auto f = [&](std::int64_t x, int k) { return (x - pos[k]) * (x - pos[k]) + g[k]; };
  auto sep = [&](int i, int k) {
    return floor_div(pos[k] * pos[k] - pos[i] * pos[i] + g[k] - g[i], 2 * (pos[k] - pos[i]));
  };
  int q = -1;
  for (int k = 0; k < count; ++k) {
    while (q >= 0 && f(t[q], s[q]) > f(t[q], k)) --q;
    if (q < 0) {
      q = 0;
      s[0] = k;
      t[0] = 0;
    } else {
      const std::int64_t w = 1 + sep(s[q], k);
      if (w < m) {
        ++q;
        s[q] = k;
        t[q] = w;
      }
    }
  }
  if (q < 0) return;
  while (t[q] >= to) --q;  // t[0] = 0: the segment holding to - 1
  for (std::int64_t u = to - 1; u >= from; --u) {
    won(u, s[q]);
    if (u == t[q]) --q;
  }
}

}  // namespace voxd::detail
