// Multi-valued solid voxelization by slice functions: the filled voxels are
// exactly the solid, each carries the documented function at its centre
// (evaluated here independently from the formulas in slice_functions.h),
// patterns rotate with the part, noise repeats for a seed and is continuous,
// threads change nothing, bad options are refused with their field's name.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "support/test_checks.h"
#include "support/slice_cases.h"
#include "support/test_meshes.h"
#include "voxd/analysis/analysis_images.h"
#include "voxd/analysis/value_images.h"
#include "voxd/byte_sink.h"
#include "voxd/error.h"
#include "voxd/voxelize/slice_functions.h"
#include "voxd/transform.h"
#include "voxd/encode/volume_format.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd {
namespace {

using test::code_of;
using test::make_grid;

constexpr auto& kAll = test::kAllSliceFunctions;

Mesh torus() {
  Mesh m = test::make_torus({0.1, -0.2, 0.05}, 1.0, 0.4, 48, 24);
  rotate_mesh(m, rotation_from_axis_angle({1.0, 0.3, 0.2}, 33.0));
  return m;
}
Mesh sphere() { return test::make_icosphere({0.3, 0.1, -0.2}, 1.1, 3); }

// A grid of `n` voxels along the mesh's longest extent, 1 voxel of padding.
Grid grid_for(const Mesh& mesh, std::int64_t n) {
  GridRequest r;
  r.resolution = n;
  r.padding = 1;
  return resolve_grid(r, bounds(mesh));
}

SliceOptions options_for(SliceFunction f) { return test::slice_case(f); }

int channel_difference(const Rgba8& p, const Rgba8& q) {
  return std::max({std::abs(p.r - q.r), std::abs(p.g - q.g), std::abs(p.b - q.b), std::abs(p.a - q.a)});
}

// ------------------------------------------------ the independent model --
// Written from the header's formulas, sharing no code with the engine.

struct Frame {
  glm::dvec3 o, u, v, w, lo, hi;
  glm::dvec3 at(const glm::dvec3& p) const {
    const glm::dvec3 d = p - o;
    return {glm::dot(d, u), glm::dot(d, v), glm::dot(d, w)};
  }
};

Frame model_frame(const Mesh& mesh, glm::dvec3 axis) {
  Frame f;
  f.w = glm::normalize(axis);
  int e = 0;
  if (std::abs(f.w.y) < std::abs(f.w[e])) e = 1;
  if (std::abs(f.w.z) < std::abs(f.w[e])) e = 2;
  glm::dvec3 ev(0.0);
  ev[e] = 1.0;
  f.u = glm::normalize(glm::cross(f.w, ev));
  f.v = glm::cross(f.w, f.u);
  const Aabb box = bounds(mesh);
  f.o = (box.min + box.max) * 0.5;
  f.lo = glm::dvec3(1e300);
  f.hi = glm::dvec3(-1e300);
  for (const auto& t : mesh.triangles)
    for (int c = 0; c < 3; ++c) {
      const glm::dvec3 q = f.at(glm::dvec3(mesh.vertices[t[static_cast<std::size_t>(c)]]));
      f.lo = glm::min(f.lo, q);
      f.hi = glm::max(f.hi, q);
    }
  return f;
}

double channel_mix(double a, double b, double t) { return std::floor(a + (b - a) * t + 0.5); }
Rgba8 model_mix(Rgba8 a, Rgba8 b, double t) {
  return {static_cast<std::uint8_t>(channel_mix(a.r, b.r, t)), static_cast<std::uint8_t>(channel_mix(a.g, b.g, t)),
          static_cast<std::uint8_t>(channel_mix(a.b, b.b, t)), static_cast<std::uint8_t>(channel_mix(a.a, b.a, t))};
}
double unit_clamp(double t) { return std::clamp(t, 0.0, 1.0); }

// The simple functions (the noise ones are checked through evaluate_slice
// and their properties).
Rgba8 model_colour(const SliceOptions& o, const Frame& f, const glm::dvec3& p) {
  const glm::dvec3 q = f.at(p);
  switch (o.function) {
    case SliceFunction::single_color: return o.color;
    case SliceFunction::color_ramp: {
      const double t = unit_clamp((q.z - f.lo.z) / (f.hi.z - f.lo.z));
      if (t < o.ramp.front().position) return o.ramp.front().color;
      if (t >= o.ramp.back().position) return o.ramp.back().color;
      std::size_t i = 0;
      for (std::size_t s = 0; s < o.ramp.size(); ++s)
        if (o.ramp[s].position <= t) i = s;
      return model_mix(o.ramp[i].color, o.ramp[i + 1].color,
                       (t - o.ramp[i].position) / (o.ramp[i + 1].position - o.ramp[i].position));
    }
    case SliceFunction::interpolated_colors: {
      const double s = unit_clamp((q.x - f.lo.x) / (f.hi.x - f.lo.x));
      const double t = unit_clamp((q.y - f.lo.y) / (f.hi.y - f.lo.y));
      const auto& c = o.corners;
      const auto ch = [&](auto get) {
        const double bottom = get(c[0]) + (get(c[1]) - get(c[0])) * s;
        const double top = get(c[2]) + (get(c[3]) - get(c[2])) * s;
        return static_cast<std::uint8_t>(std::floor(bottom + (top - bottom) * t + 0.5));
      };
      return {ch([](Rgba8 x) { return double(x.r); }), ch([](Rgba8 x) { return double(x.g); }),
              ch([](Rgba8 x) { return double(x.b); }), ch([](Rgba8 x) { return double(x.a); })};
    }
    case SliceFunction::checker: {
      const long n = std::lround(std::floor(q.x / o.checker_size) + std::floor(q.y / o.checker_size) +
                                 std::floor(q.z / o.checker_size));
      return o.checker_colors[static_cast<std::size_t>(n & 1)];
    }
    default: ADD_FAILURE() << "no model for " << to_string(o.function); return {};
  }
}

// The noise functions from the header's description alone: splitmix64,
// Fisher-Yates, and Perlin's reference improved noise.
struct ModelNoise {
  int p[512];
  explicit ModelNoise(std::uint64_t seed) {
    int q[256];
    for (int i = 0; i < 256; ++i) q[i] = i;
    std::uint64_t state = seed;
    for (int i = 255; i >= 1; --i) {
      state += 0x9e3779b97f4a7c15ull;
      std::uint64_t z = state;
      z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
      z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
      z ^= z >> 31;
      std::swap(q[i], q[z % static_cast<std::uint64_t>(i + 1)]);
    }
    for (int i = 0; i < 512; ++i) p[i] = q[i & 255];
  }
  static double fade(double t) { return t * t * t * (t * (t * 6 - 15) + 10); }
  static double lerp(double t, double a, double b) { return a + t * (b - a); }
  static double grad(int hash, double x, double y, double z) {
    const int h = hash & 15;
    const double u = h < 8 ? x : y, v = h < 4 ? y : h == 12 || h == 14 ? x : z;
    return ((h & 1) == 0 ? u : -u) + ((h & 2) == 0 ? v : -v);
  }
  double noise(double x, double y, double z) const {
    const int X = static_cast<int>(std::floor(x)) & 255, Y = static_cast<int>(std::floor(y)) & 255,
              Z = static_cast<int>(std::floor(z)) & 255;
    x -= std::floor(x);
    y -= std::floor(y);
    z -= std::floor(z);
    const double u = fade(x), v = fade(y), w = fade(z);
    const int A = p[X] + Y, AA = p[A] + Z, AB = p[A + 1] + Z, B = p[X + 1] + Y, BA = p[B] + Z, BB = p[B + 1] + Z;
    return lerp(w, lerp(v, lerp(u, grad(p[AA], x, y, z), grad(p[BA], x - 1, y, z)),
                        lerp(u, grad(p[AB], x, y - 1, z), grad(p[BB], x - 1, y - 1, z))),
                lerp(v, lerp(u, grad(p[AA + 1], x, y, z - 1), grad(p[BA + 1], x - 1, y, z - 1)),
                     lerp(u, grad(p[AB + 1], x, y - 1, z - 1), grad(p[BB + 1], x - 1, y - 1, z - 1))));
  }
};

Rgba8 model_noise_colour(const SliceOptions& o, const Frame& f, const ModelNoise& n, const glm::dvec3& p) {
  const glm::dvec3 q = f.at(p);
  const glm::dvec3 s = q / o.noise_scale;
  double T = 0, F = 0;
  for (int k = 0; k < o.octaves; ++k) {
    const double m = std::ldexp(1.0, k);
    const double v = n.noise(s.x * m, s.y * m, s.z * m);
    T += std::abs(v) / m;
    F += v / m;
  }
  const double pi = std::numbers::pi;
  double t = 0;
  if (o.function == SliceFunction::wood)
    t = 0.5 - 0.5 * std::cos(2 * pi * (std::hypot(q.x, q.y) / o.period + o.turbulence * T));
  else if (o.function == SliceFunction::marble)
    t = 0.5 + 0.5 * std::sin(2 * pi * q.z / o.period + 2 * pi * o.turbulence * T);
  else
    t = unit_clamp(0.5 + 0.5 * F);
  const std::size_t count = o.noise_colors.size();
  const double x = t * static_cast<double>(count - 1);
  const std::size_t i = std::min(static_cast<std::size_t>(x), count - 2);
  return model_mix(o.noise_colors[i], o.noise_colors[i + 1], x - static_cast<double>(i));
}

// True when a checker cell boundary passes within `eps` of the point's frame
// coordinates (rounding may then put it in either cell).
bool near_checker_boundary(const SliceOptions& o, const Frame& f, const glm::dvec3& p, double eps = 1e-9) {
  const glm::dvec3 q = f.at(p) / o.checker_size;
  for (int a = 0; a < 3; ++a)
    if (std::abs(q[a] - std::round(q[a])) < eps) return true;
  return false;
}

// -------------------------------------------------------------- tests --

TEST(SliceFunctions, NamesRoundTrip) {
  const char* names[] = {"single_color", "color_ramp", "interpolated_colors", "checker", "wood", "marble", "rock", "custom"};
  for (std::size_t i = 0; i < 8; ++i) {
    EXPECT_STREQ(to_string(kAll[i]), names[i]);
    EXPECT_EQ(slice_function_from_string(names[i]), kAll[i]);
  }
  EXPECT_FALSE(slice_function_from_string("Marble").has_value());
  EXPECT_FALSE(slice_function_from_string("").has_value());
}

TEST(SliceFunctions, FrameFollowsTheDocumentedRule) {
  const Mesh m = torus();
  for (const glm::dvec3 axis : {glm::dvec3(0, 0, 1), glm::dvec3(0, 3, 0), glm::dvec3(-2, 0, 0),
                                glm::dvec3(0.3, -0.5, 1.0), glm::dvec3(1, 1, 1), glm::dvec3(1e-200, 0, 1e-200)}) {
    SCOPED_TRACE(axis.x);
    const SliceFrame f = make_slice_frame(m, axis);
    const Frame g = model_frame(m, axis.x == 1e-200 ? glm::dvec3(1, 0, 1) : axis);
    for (int a = 0; a < 3; ++a) {
      EXPECT_NEAR(f.w[a], g.w[a], 1e-15);
      EXPECT_NEAR(f.u[a], g.u[a], 1e-15);
      EXPECT_NEAR(f.v[a], g.v[a], 1e-15);
      EXPECT_NEAR(f.origin[a], g.o[a], 1e-12);
      EXPECT_NEAR(f.lo[a], g.lo[a], 1e-12);
      EXPECT_NEAR(f.hi[a], g.hi[a], 1e-12);
    }
    EXPECT_NEAR(glm::dot(glm::cross(f.u, f.v), f.w), 1.0, 1e-15);  // right-handed, orthonormal
  }
  // Axis z: u = y, v = -x (e = x).
  const SliceFrame z = make_slice_frame(m, {0, 0, 5});
  EXPECT_EQ(z.u, glm::dvec3(0, 1, 0));
  EXPECT_EQ(z.v, glm::dvec3(-1, 0, 0));
  EXPECT_EQ(z.w, glm::dvec3(0, 0, 1));
}

TEST(SliceVoxelize, FilledVoxelsAreExactlyTheSolidForEveryFunction) {
  for (const auto& [name, mesh] : {std::pair<const char*, Mesh>{"torus", torus()}, {"sphere", sphere()}}) {
    const Grid g = grid_for(mesh, 41);
    for (const InsideTest inside : {InsideTest::parity, InsideTest::winding}) {
      const BitVolume solid = voxelize(mesh, g, {VoxelMode::solid, inside, 2});
      ASSERT_GT(solid.count(), 1000u);
      for (const SliceFunction f : kAll) {
        SCOPED_TRACE(std::string(name) + " " + to_string(f) + " " + to_string(inside));
        SliceOptions o = options_for(f);
        o.inside = inside;
        const DenseVolume<Rgba8> c = voxelize_slice(mesh, g, o);
        ASSERT_EQ(c.values().size(), g.voxel_count());
        std::uint64_t mismatches = 0;
        for (std::int64_t k = 0; k < g.dims.z; ++k)
          for (std::int64_t j = 0; j < g.dims.y; ++j)
            for (std::int64_t i = 0; i < g.dims.x; ++i) {
              const Rgba8 v = c.at(i, j, k);
              const bool inside_voxel = solid.get(i, j, k);
              if ((v.a > 0) != inside_voxel || (!inside_voxel && !(v == Rgba8{}))) ++mismatches;
            }
        EXPECT_EQ(mismatches, 0u);
      }
    }
  }
}

TEST(SliceVoxelize, SimpleFunctionsMatchTheDocumentedFormulasAtEveryCentre) {
  for (const auto& [name, mesh] : {std::pair<const char*, Mesh>{"torus", torus()}, {"sphere", sphere()}}) {
    const Grid g = grid_for(mesh, 48);
    for (const SliceFunction f : {SliceFunction::single_color, SliceFunction::color_ramp,
                                  SliceFunction::interpolated_colors, SliceFunction::checker}) {
      for (const glm::dvec3 axis : {glm::dvec3(0.3, -0.5, 1.0), glm::dvec3(0, 0, 1), glm::dvec3(1, 2, 0)}) {
        SCOPED_TRACE(std::string(name) + " " + to_string(f) + " axis " + std::to_string(axis.x) + "," +
                     std::to_string(axis.y) + "," + std::to_string(axis.z));
        SliceOptions o = options_for(f);
        o.axis = axis;
        const Frame model = model_frame(mesh, axis);
        const SliceFrame frame = make_slice_frame(mesh, axis);
        const DenseVolume<Rgba8> c = voxelize_slice(mesh, g, o);
        std::uint64_t filled = 0, off = 0, worst = 0;
        for (std::int64_t k = 0; k < g.dims.z; ++k)
          for (std::int64_t j = 0; j < g.dims.y; ++j)
            for (std::int64_t i = 0; i < g.dims.x; ++i) {
              const Rgba8 v = c.at(i, j, k);
              if (v.a == 0) continue;
              ++filled;
              const glm::dvec3 p = g.center(i, j, k);
              if (f == SliceFunction::checker && near_checker_boundary(o, model, p)) continue;
              const int d = channel_difference(v, model_colour(o, model, p));
              // The engine steps the frame coordinates along a row: its last
              // bits may round a channel the other way, never further.
              worst = std::max<std::uint64_t>(worst, static_cast<std::uint64_t>(d));
              if (d > 0) ++off;
              EXPECT_LE(channel_difference(v, evaluate_slice(o, frame, p)), 1);
            }
        EXPECT_GT(filled, 1000u);
        EXPECT_LE(worst, 1u);
        EXPECT_LE(off, filled / 100);  // ties (x.5 before rounding) at symmetric centres
      }
    }
  }
}

TEST(SliceVoxelize, ColorRampEndsTakeTheEndStops) {
  // A box 10 long along z: voxel layer k has t = (k + 1/2) / 10.
  const Mesh box = test::make_box({0, 0, 0}, {4, 5, 10});
  const Grid g = make_grid({4, 5, 10});
  SliceOptions o;
  o.function = SliceFunction::color_ramp;
  const Rgba8 red{255, 0, 0, 255}, blue{0, 0, 255, 128};
  o.ramp = {{0.2, red}, {0.8, blue}};
  const DenseVolume<Rgba8> c = voxelize_slice(box, g, o);
  for (std::int64_t j = 0; j < 5; ++j)
    for (std::int64_t i = 0; i < 4; ++i) {
      EXPECT_EQ(c.at(i, j, 0), red);  // t = 0.05
      EXPECT_EQ(c.at(i, j, 1), red);  // t = 0.15
      EXPECT_EQ(c.at(i, j, 8), blue);
      EXPECT_EQ(c.at(i, j, 9), blue);
      EXPECT_EQ(c.at(i, j, 5), model_mix(red, blue, (0.55 - 0.2) / 0.6));
    }
  // Stops at 0 and 1: the end layers are within half a voxel's share of the end colours.
  o.ramp = {{0.0, red}, {1.0, blue}};
  const DenseVolume<Rgba8> d = voxelize_slice(box, g, o);
  EXPECT_EQ(d.at(0, 0, 0), model_mix(red, blue, 0.05));
  EXPECT_EQ(d.at(3, 4, 9), model_mix(red, blue, 0.95));
  // Reversing the axis reverses the ramp.
  o.axis = {0, 0, -1};
  const DenseVolume<Rgba8> e = voxelize_slice(box, g, o);
  EXPECT_EQ(e.at(2, 2, 0), d.at(2, 2, 9));
  EXPECT_EQ(e.at(2, 2, 9), d.at(2, 2, 0));
}

TEST(SliceVoxelize, CheckerCellsOfTheGivenSizeAlternate) {
  // Box [0, 8]^3 (frame origin at its centre, 4), axis z, cells of 2 voxels:
  // cell boundaries fall on even voxel boundaries.
  const Mesh box = test::make_box({0, 0, 0}, {8, 8, 8});
  const Grid g = make_grid({8, 8, 8});
  SliceOptions o;
  o.function = SliceFunction::checker;
  o.checker_size = 2.0;
  o.checker_colors = {Rgba8{10, 10, 10, 255}, Rgba8{240, 240, 240, 255}};
  const DenseVolume<Rgba8> c = voxelize_slice(box, g, o);
  for (std::int64_t k = 0; k < 8; ++k)
    for (std::int64_t j = 0; j < 8; ++j)
      for (std::int64_t i = 0; i < 8; ++i) {
        const Rgba8 v = c.at(i, j, k);
        ASSERT_TRUE(v == o.checker_colors[0] || v == o.checker_colors[1]);
        const auto partner = [](std::int64_t x) { return x ^ 1; };  // same cell
        EXPECT_EQ(c.at(partner(i), j, k), v);
        EXPECT_EQ(c.at(i, partner(j), k), v);
        EXPECT_EQ(c.at(i, j, partner(k)), v);
        if (i + 2 < 8) { EXPECT_NE(c.at(i + 2, j, k), v); }  // the next cell
        if (j + 2 < 8) { EXPECT_NE(c.at(i, j + 2, k), v); }
        if (k + 2 < 8) { EXPECT_NE(c.at(i, j, k + 2), v); }
      }
  // Centre (4.5, 4.5, 4.5): (a, b, c) = (y - 4, -(x - 4), z - 4) = (0.5, -0.5, 0.5),
  // n = 0 - 1 + 0 odd.
  EXPECT_EQ(c.at(4, 4, 4), o.checker_colors[1]);
  EXPECT_EQ(c.at(4, 3, 4), o.checker_colors[0]);  // a = -0.5: n = -2
}

TEST(SliceVoxelize, CustomLookupCellsSplitThePartsExtentEvenly) {
  // Box [0, 8]^3, axis z: (a, b, c) = (y - 4, -(x - 4), z - 4), each
  // spanning [-4, 4]. Two cells along a split at y = 4, four along c at
  // every 2 voxels of z.
  const Mesh box = test::make_box({0, 0, 0}, {8, 8, 8});
  SliceOptions o;
  o.function = SliceFunction::custom;
  o.lookup_dims = {2, 1, 4};
  for (std::uint8_t c = 0; c < 8; ++c) o.lookup_colors.push_back(Rgba8{static_cast<std::uint8_t>(10 * c), 0, 0, 255});
  o.lookup_colors.erase(o.lookup_colors.begin());  // the default's single cell
  ASSERT_EQ(o.lookup_colors.size(), 8u);
  const DenseVolume<Rgba8> c = voxelize_slice(box, make_grid({8, 8, 8}), o);
  for (std::int64_t k = 0; k < 8; ++k)
    for (std::int64_t j = 0; j < 8; ++j)
      for (std::int64_t i = 0; i < 8; ++i) {
        const std::size_t cell = static_cast<std::size_t>(j >= 4) + 2 * static_cast<std::size_t>(k / 2);
        ASSERT_EQ(c.at(i, j, k), o.lookup_colors[cell]) << i << "," << j << "," << k;
      }
  // Refusals name the field and what it must be.
  o.lookup_dims = {2, 1, 65};
  EXPECT_THROW(validate(o), Error);
  o.lookup_dims = {2, 1, 4};
  o.lookup_colors.pop_back();
  try {
    validate(o);
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("nx * ny * nz = 8"), std::string::npos) << e.what();
  }
}

// The box and a tilted torus, and the same rotated by -90 degrees about x,
// (x, y, z) -> (x, z, -y): exact in floating point, as is the grid mapping
// voxel (i, j, k) to (i, k, ny - 1 - j).
Mesh rotated_exactly(Mesh m) {
  for (glm::vec3& p : m.vertices) p = glm::vec3(p.x, p.z, -p.y);
  return m;
}

TEST(SliceVoxelize, RotatingThePartWithTheAxisRotatesThePatternAndNothingElse) {
  const Mesh part = test::concat({test::make_box({1.75, -1.0, -1.0}, {2.5, 0.5, 3.0}), torus()});
  const Grid g = make_grid({40, 36, 44}, {-1.75, -1.75, -1.75}, 0.125);
  const Mesh turned = rotated_exactly(part);
  const Grid h = make_grid({g.dims.x, g.dims.z, g.dims.y},
                           {g.origin.x, g.origin.z, -(g.origin.y + static_cast<double>(g.dims.y) * g.voxel_size)},
                           g.voxel_size);
  for (const glm::dvec3 axis : {glm::dvec3(0, 0, 1), glm::dvec3(0.3, 0.5, 1.0)}) {
    const glm::dvec3 turned_axis(axis.x, axis.z, -axis.y);
    for (const SliceFunction f : kAll) {
      SCOPED_TRACE(std::string(to_string(f)) + " axis.x " + std::to_string(axis.x));
      SliceOptions o = options_for(f);
      o.axis = axis;
      const DenseVolume<Rgba8> a = voxelize_slice(part, g, o);
      o.axis = turned_axis;
      const DenseVolume<Rgba8> b = voxelize_slice(turned, h, o);
      std::uint64_t filled = 0, differ = 0, far = 0;
      for (std::int64_t k = 0; k < g.dims.z; ++k)
        for (std::int64_t j = 0; j < g.dims.y; ++j)
          for (std::int64_t i = 0; i < g.dims.x; ++i) {
            const Rgba8 p = a.at(i, j, k), q = b.at(i, k, g.dims.y - 1 - j);
            ASSERT_EQ(p.a > 0, q.a > 0) << i << " " << j << " " << k;
            filled += p.a > 0;
            const int d = channel_difference(p, q);
            differ += d > 0;
            far += d > 1;
          }
      EXPECT_GT(filled, 3000u);
      // Exactly the same, but for the last bit of a rotated frame's
      // coordinates rounding a channel (or, on a cell boundary, a checker
      // cell) the other way at a handful of voxels.
      if (axis.x == 0) { EXPECT_EQ(differ, 0u); }
      EXPECT_LE(differ, filled / 1000);
      if (f != SliceFunction::checker) { EXPECT_EQ(far, 0u); }
    }
  }
}

TEST(SliceVoxelize, NoiseFunctionsAreTheFunctionAtTheCentreRepeatableAndContinuous) {
  const Mesh mesh = torus();
  const Grid g = grid_for(mesh, 50);
  for (const SliceFunction f : {SliceFunction::wood, SliceFunction::marble, SliceFunction::rock}) {
    SCOPED_TRACE(to_string(f));
    SliceOptions o = options_for(f);
    const SliceFrame frame = make_slice_frame(mesh, o.axis);
    const DenseVolume<Rgba8> c = voxelize_slice(mesh, g, o);
    // The function at each centre.
    std::uint64_t filled = 0, worst = 0;
    std::vector<Rgba8> distinct;
    for (std::int64_t k = 0; k < g.dims.z; ++k)
      for (std::int64_t j = 0; j < g.dims.y; ++j)
        for (std::int64_t i = 0; i < g.dims.x; ++i) {
          const Rgba8 v = c.at(i, j, k);
          if (v.a == 0) continue;
          ++filled;
          worst = std::max<std::uint64_t>(worst, static_cast<std::uint64_t>(
                                                     channel_difference(v, evaluate_slice(o, frame, g.center(i, j, k)))));
          if (distinct.size() < 64 && std::find(distinct.begin(), distinct.end(), v) == distinct.end())
            distinct.push_back(v);
        }
    EXPECT_GT(filled, 1000u);
    EXPECT_LE(worst, 1u);
    EXPECT_GE(distinct.size(), 32u) << "the pattern should vary";

    // The documented formulas, evaluated here from scratch, agree: a channel
    // may round the other way where the engine's stepped coordinates differ
    // in their last bits, at a few voxels.
    const Frame model = model_frame(mesh, o.axis);
    for (const std::uint64_t seed : {o.seed, std::uint64_t{0}, std::uint64_t{0xfeedbeefcafe}}) {
      SliceOptions s = o;
      s.seed = seed;
      const DenseVolume<Rgba8> e = seed == o.seed ? DenseVolume<Rgba8>(c) : voxelize_slice(mesh, g, s);
      const ModelNoise noise(seed);
      std::uint64_t off = 0, far = 0;
      for (std::int64_t k = 0; k < g.dims.z; ++k)
        for (std::int64_t j = 0; j < g.dims.y; ++j)
          for (std::int64_t i = 0; i < g.dims.x; ++i) {
            const Rgba8 v = e.at(i, j, k);
            if (v.a == 0) continue;
            const int d = channel_difference(v, model_noise_colour(s, model, noise, g.center(i, j, k)));
            off += d > 0;
            far += d > 1;
          }
      EXPECT_EQ(far, 0u) << "seed " << seed;
      EXPECT_LE(off, filled / 100) << "seed " << seed;
    }

    // Repeatable for a seed; another seed gives another pattern.
    EXPECT_TRUE(voxelize_slice(mesh, g, o).values() == c.values());
    SliceOptions other = o;
    other.seed = 8;
    const DenseVolume<Rgba8> d = voxelize_slice(mesh, g, other);
    std::uint64_t changed = 0;
    for (std::size_t n = 0; n < c.values().size(); ++n) changed += channel_difference(c.values()[n], d.values()[n]) > 2;
    EXPECT_GT(changed, filled / 4);

    // Continuous: a displacement of 1e-7 model units changes no channel by
    // more than a rounding step.
    int worst_tiny = 0;
    for (std::int64_t k = 0; k < g.dims.z; ++k)
      for (std::int64_t j = 0; j < g.dims.y; ++j)
        for (std::int64_t i = 0; i < g.dims.x; ++i) {
          if (c.at(i, j, k).a == 0) continue;
          const glm::dvec3 p = g.center(i, j, k);
          const glm::dvec3 q = p + glm::dvec3(1e-7, -0.6e-7, 0.8e-7);
          worst_tiny = std::max(worst_tiny, channel_difference(evaluate_slice(o, frame, p), evaluate_slice(o, frame, q)));
        }
    EXPECT_LE(worst_tiny, 1);
  }
}

// The largest difference between face neighbours of filled voxels.
int largest_neighbour_step(const DenseVolume<Rgba8>& c) {
  const glm::i64vec3 n = c.grid().dims;
  int worst = 0;
  for (std::int64_t k = 0; k + 1 < n.z; ++k)
    for (std::int64_t j = 0; j + 1 < n.y; ++j)
      for (std::int64_t i = 0; i + 1 < n.x; ++i) {
        const Rgba8 v = c.at(i, j, k);
        if (v.a == 0) continue;
        for (const Rgba8 w : {c.at(i + 1, j, k), c.at(i, j + 1, k), c.at(i, j, k + 1)})
          if (w.a != 0) worst = std::max(worst, channel_difference(v, w));
      }
  return worst;
}

TEST(SliceVoxelize, NoiseFunctionsHaveNoJumps) {
  // Halving the voxel size halves the largest step between neighbours of a
  // continuous (Lipschitz) function, up to rounding; a jump would keep it.
  const Mesh mesh = torus();
  for (const SliceFunction f : {SliceFunction::wood, SliceFunction::marble, SliceFunction::rock}) {
    SCOPED_TRACE(to_string(f));
    SliceOptions o = options_for(f);
    o.noise_scale = 1.0;
    o.period = 1.0;
    o.octaves = 2;
    const int coarse = largest_neighbour_step(voxelize_slice(mesh, grid_for(mesh, 40), o));
    const int fine = largest_neighbour_step(voxelize_slice(mesh, grid_for(mesh, 80), o));
    EXPECT_GT(coarse, 4);
    EXPECT_LE(fine, 0.75 * coarse + 2) << "coarse " << coarse;
    EXPECT_GE(fine, 0.3 * coarse - 2) << "coarse " << coarse;
  }
}

TEST(SliceVoxelize, TheResultDoesNotDependOnTheThreadCount) {
  const Mesh mesh = torus();
  const Grid g = grid_for(mesh, 60);
  for (const SliceFunction f : kAll) {
    SCOPED_TRACE(to_string(f));
    SliceOptions o = options_for(f);
    o.threads = 1;
    const DenseVolume<Rgba8> one = voxelize_slice(mesh, g, o);
    for (const int t : {2, 3, 8}) {
      o.threads = t;
      EXPECT_TRUE(voxelize_slice(mesh, g, o).values() == one.values()) << t << " threads";
    }
  }
}

TEST(SliceColours, SectionsAndPreviewsOfASolidAreTheColouredVolumesOwn) {
  // Colouring a solid already made, a section or a view at a time, must give
  // the bytes of the coloured volume's own images, for every function, every
  // section axis and views from several sides, on a grid of odd sizes.
  const Mesh mesh = torus();
  const Grid g = grid_for(mesh, 41);
  ASSERT_TRUE(g.dims.x % 2 == 1 || g.dims.y % 2 == 1 || g.dims.z % 2 == 1) << "an odd size along some axis";
  const BitVolume solid = voxelize(mesh, g, {VoxelMode::solid, InsideTest::parity, 2});
  for (const SliceFunction f : kAll) {
    SCOPED_TRACE(to_string(f));
    const SliceOptions o = options_for(f);
    const DenseVolume<Rgba8> volume = voxelize_slice(mesh, g, o);
    const SliceColours colours(o, make_slice_frame(mesh, o.axis), g);
    std::uint64_t differ = 0, filled = 0;
    for (std::int64_t k = 0; k < g.dims.z; ++k)
      for (std::int64_t j = 0; j < g.dims.y; ++j)
        for (std::int64_t i = 0; i < g.dims.x; ++i)
          if (solid.get(i, j, k)) ++filled, differ += colours.at(i, j, k) == volume.at(i, j, k) ? 0 : 1;
    ASSERT_GT(filled, 1000u);
    EXPECT_EQ(differ, 0u);
    for (int axis = 0; axis < 3; ++axis)
      for (const std::int64_t index : {std::int64_t{0}, g.dims[axis] / 2, g.dims[axis] / 3 + 1}) {
        SCOPED_TRACE("axis " + std::to_string(axis) + " index " + std::to_string(index));
        EXPECT_EQ(slice_section_png(solid, colours, axis, index, {{"voxd:source", "t"}}, 3),
                  colour_section_png(volume, axis, index, {{"voxd:source", "t"}}));
        // Encoded fast for an editor: other bytes, the same pixels.
        EXPECT_EQ(test::decode_png(slice_section_png(solid, colours, axis, index, {}, 2, PngCompression::fast))["pixels"],
                  test::decode_png(colour_section_png(volume, axis, index))["pixels"]);
      }
    for (const View view : {View{2, true}, View{0, false}, View{1, true}}) {
      SCOPED_TRACE(to_string(view));
      EXPECT_EQ(slice_preview_png(solid, colours, view, {}, 2), colour_preview_png(solid, volume, view, {}, 2));
      EXPECT_EQ(test::decode_png(slice_preview_png(render_preview(solid, view), g, colours, view, {}, 2, 0,
                                                   PngCompression::fast))["pixels"],
                test::decode_png(colour_preview_png(solid, volume, view))["pixels"]);
    }
  }
  const SliceColours other(options_for(SliceFunction::wood), make_slice_frame(mesh, {0, 0, 1}), grid_for(mesh, 30));
  EXPECT_EQ(code_of([&] { slice_section_png(solid, other, 2, 3); }), ErrorCode::invalid_argument);
  EXPECT_EQ(code_of([&] { slice_preview_png(solid, other, View{2, true}); }), ErrorCode::invalid_argument);
  EXPECT_EQ(code_of([&] { slice_section_png(solid, SliceColours(options_for(SliceFunction::rock), make_slice_frame(mesh, {0, 0, 1}), g), 2, g.dims.z); }),
            ErrorCode::invalid_argument);
}

TEST(SliceVoxelize, BadOptionsAreRefusedWithTheFieldAndWhatItMustBe) {
  const Mesh mesh = sphere();
  const Grid g = grid_for(mesh, 8);
  const auto refused = [&](SliceOptions o, const std::string& expected) {
    SCOPED_TRACE(expected);
    std::string message;
    EXPECT_EQ(code_of([&] { voxelize_slice(mesh, g, o); }, &message), ErrorCode::invalid_argument);
    EXPECT_NE(message.find(expected), std::string::npos) << message;
    EXPECT_EQ(code_of([&] { evaluate_slice(o, SliceFrame{}, {0, 0, 0}); }), ErrorCode::invalid_argument);
  };
  SliceOptions o = options_for(SliceFunction::single_color);
  o.axis = {0, 0, 0};
  refused(o, "axis must be a finite, non-zero direction");
  o.axis = {0, std::numeric_limits<double>::quiet_NaN(), 1};
  refused(o, "axis must be a finite, non-zero direction");
  EXPECT_EQ(code_of([&] { make_slice_frame(mesh, {0, 0, 0}); }), ErrorCode::invalid_argument);

  o = options_for(SliceFunction::single_color);
  o.color.a = 0;
  refused(o, "color has alpha 0");
  o = options_for(SliceFunction::color_ramp);
  o.ramp.resize(1);
  refused(o, "at least 2 ramp stops");
  o = options_for(SliceFunction::color_ramp);
  o.ramp[3].position = 1.5;
  refused(o, "ramp[3].position must be in [0, 1]");
  o = options_for(SliceFunction::color_ramp);
  o.ramp[1].position = 0.9;
  refused(o, "ramp[2].position 0.400000 is below the previous stop's 0.900000");
  o = options_for(SliceFunction::color_ramp);
  o.ramp[2].color.a = 0;
  refused(o, "ramp[2].color has alpha 0");
  o = options_for(SliceFunction::interpolated_colors);
  o.corners[3].a = 0;
  refused(o, "corners[3] has alpha 0");
  o = options_for(SliceFunction::checker);
  o.checker_size = 0;
  refused(o, "checker_size must be a finite number > 0");
  o.checker_size = std::numeric_limits<double>::infinity();
  refused(o, "checker_size must be a finite number > 0");
  o = options_for(SliceFunction::checker);
  o.checker_colors[1].a = 0;
  refused(o, "checker_colors[1] has alpha 0");
  o = options_for(SliceFunction::marble);
  o.noise_scale = -1;
  refused(o, "noise_scale must be a finite number > 0");
  o = options_for(SliceFunction::wood);
  o.period = 0;
  refused(o, "period must be a finite number > 0 (the spacing of the rings");
  o = options_for(SliceFunction::marble);
  o.octaves = 0;
  refused(o, "octaves must be 1..16, got 0");
  o.octaves = 17;
  refused(o, "octaves must be 1..16, got 17");
  o = options_for(SliceFunction::marble);
  o.turbulence = -0.5;
  refused(o, "turbulence must be a finite number >= 0");
  o = options_for(SliceFunction::rock);
  o.noise_colors.resize(1);
  refused(o, "rock needs 2 or 3 noise_colors, got 1");
  o.noise_colors.assign(4, Rgba8{1, 2, 3, 4});
  refused(o, "rock needs 2 or 3 noise_colors, got 4");
  o = options_for(SliceFunction::wood);
  o.noise_colors[1].a = 0;
  refused(o, "noise_colors[1] has alpha 0");

  // Fields of other functions are not checked.
  o = options_for(SliceFunction::single_color);
  o.ramp.clear();
  o.checker_size = -1;
  o.noise_colors.clear();
  EXPECT_NO_THROW(voxelize_slice(mesh, g, o));
  // Rock ignores period and turbulence.
  o = options_for(SliceFunction::rock);
  o.period = 0;
  o.turbulence = -1;
  EXPECT_NO_THROW(voxelize_slice(mesh, g, o));
}

TEST(SliceVoxelize, ReportsProgressAndHonoursCancellation) {
  const Mesh mesh = torus();
  const Grid g = grid_for(mesh, 40);
  JobControl control;
  control.set_span(0.2, 0.6);
  voxelize_slice(mesh, g, options_for(SliceFunction::marble), &control);
  EXPECT_NEAR(control.progress(), 0.6, 1e-12);
  EXPECT_EQ(control.span_begin(), 0.2);  // the caller's span is left as it was
  EXPECT_EQ(control.span_end(), 0.6);
  JobControl cancelled;
  cancelled.request_cancel();
  EXPECT_EQ(code_of([&] { voxelize_slice(mesh, g, options_for(SliceFunction::marble), &cancelled); }),
            ErrorCode::cancelled);
}

TEST(SliceVoxelize, EmptyMeshGivesAnEmptyVolume) {
  const Grid g = make_grid({5, 4, 3});
  const DenseVolume<Rgba8> c = voxelize_slice(Mesh{}, g, options_for(SliceFunction::color_ramp));
  ASSERT_EQ(c.values().size(), 60u);
  for (const Rgba8& v : c.values()) EXPECT_EQ(v, Rgba8{});
}

TEST(SliceVoxelize, RgbaRleRoundTrips) {
  const Mesh mesh = torus();
  const Grid g = grid_for(mesh, 40);
  const DenseVolume<Rgba8> c = voxelize_slice(mesh, g, options_for(SliceFunction::color_ramp));
  VectorSink sink;
  write_rle(c, sink);
  const DenseVolume<Rgba8> back = read_rle_rgba8(sink.data);
  EXPECT_EQ(back.grid().dims, g.dims);
  EXPECT_TRUE(back.values() == c.values());
}

}  // namespace
}  // namespace voxd
