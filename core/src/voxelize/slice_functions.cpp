// Multi-valued solid voxelization by slice functions (after Liao): the solid,
// then the slice function at the centre of each of its voxels. Formulas and
// parameters in voxd/voxelize/slice_functions.h.
#include "voxd/voxelize/slice_functions.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <glm/common.hpp>

#include "voxd/error.h"
#include "voxd/parallel.h"
#include "voxelize/perlin_noise.h"

namespace voxd {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

[[noreturn]] void bad(const std::string& message) { throw Error(ErrorCode::invalid_argument, message); }

std::string text(const glm::dvec3& v) {
  std::ostringstream out;
  out << '(' << v.x << ", " << v.y << ", " << v.z << ')';
  return out.str();
}

bool finite(const glm::dvec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

void check_alpha(const Rgba8& c, const std::string& field) {
  if (c.a == 0)
    bad(field + " has alpha 0; colours need alpha 1..255 (alpha 0 marks the empty voxels outside the part)");
}

void check_size(double value, const char* field, const char* what) {
  if (!(std::isfinite(value) && value > 0.0))
    bad(std::string(field) + " must be a finite number > 0 (" + what + ", in model units), got " +
        std::to_string(value));
}

void check_axis(const glm::dvec3& axis) {
  if (!finite(axis) || (axis.x == 0.0 && axis.y == 0.0 && axis.z == 0.0))
    bad("axis must be a finite, non-zero direction (the slicing direction, e.g. (0, 0, 1)), got " + text(axis));
}

// mix(c0, c1, t) per channel: floor(c0 + (c1 - c0) t + 1/2), t in [0, 1].
inline std::uint8_t mix_channel(std::uint8_t c0, std::uint8_t c1, double t) {
  const double a = c0;
  return static_cast<std::uint8_t>(static_cast<int>(a + (static_cast<double>(c1) - a) * t + 0.5));
}
inline Rgba8 mix(const Rgba8& c0, const Rgba8& c1, double t) {
  return {mix_channel(c0.r, c1.r, t), mix_channel(c0.g, c1.g, t), mix_channel(c0.b, c1.b, t),
          mix_channel(c0.a, c1.a, t)};
}

inline double clamp01(double t) { return t > 0.0 ? (t < 1.0 ? t : 1.0) : 0.0; }

}  // namespace

namespace detail {

// The function of validated options, prepared once (the noise's table, the
// extents' reciprocals) and evaluated at frame coordinates, on any thread.
class SliceShader {
 public:
  SliceShader(const SliceOptions& options, const SliceFrame& frame) : o_(options), frame_(frame) {
    const glm::dvec3 extent = frame.hi - frame.lo;
    for (int i = 0; i < 3; ++i) inv_extent_[i] = extent[i] > 0.0 ? 1.0 / extent[i] : 0.0;
    inv_cell_ = 1.0 / options.checker_size;
    inv_scale_ = 1.0 / options.noise_scale;
    inv_period_ = 1.0 / options.period;
    if (o_.function == SliceFunction::wood || o_.function == SliceFunction::marble ||
        o_.function == SliceFunction::rock)
      noise_.emplace(options.seed);
  }

  Rgba8 shade(const glm::dvec3& abc) const {
    switch (o_.function) {
      case SliceFunction::single_color: return o_.color;
      case SliceFunction::color_ramp: return ramp_stops(clamp01((abc.z - frame_.lo.z) * inv_extent_.z));
      case SliceFunction::interpolated_colors: {
        const double s = clamp01((abc.x - frame_.lo.x) * inv_extent_.x);
        const double t = clamp01((abc.y - frame_.lo.y) * inv_extent_.y);
        // mix of mixes in doubles, rounded once: the bilinear value.
        Rgba8 out;
        const auto& c = o_.corners;
        const auto channel = [s, t](std::uint8_t c0, std::uint8_t c1, std::uint8_t c2, std::uint8_t c3) {
          const double bottom = c0 + (static_cast<double>(c1) - c0) * s;
          const double top = c2 + (static_cast<double>(c3) - c2) * s;
          return static_cast<std::uint8_t>(static_cast<int>(bottom + (top - bottom) * t + 0.5));
        };
        out.r = channel(c[0].r, c[1].r, c[2].r, c[3].r);
        out.g = channel(c[0].g, c[1].g, c[2].g, c[3].g);
        out.b = channel(c[0].b, c[1].b, c[2].b, c[3].b);
        out.a = channel(c[0].a, c[1].a, c[2].a, c[3].a);
        return out;
      }
      case SliceFunction::checker: {
        const double n = std::floor(abc.x * inv_cell_) + std::floor(abc.y * inv_cell_) + std::floor(abc.z * inv_cell_);
        return o_.checker_colors[std::fmod(n, 2.0) == 0.0 ? 0 : 1];
      }
      case SliceFunction::wood: {
        const double r = std::sqrt(abc.x * abc.x + abc.y * abc.y);
        const double T = noise_->turbulence(abc.x * inv_scale_, abc.y * inv_scale_, abc.z * inv_scale_, o_.octaves);
        return ramp_even(0.5 - 0.5 * std::cos(kTwoPi * (r * inv_period_ + o_.turbulence * T)));
      }
      case SliceFunction::marble: {
        const double T = noise_->turbulence(abc.x * inv_scale_, abc.y * inv_scale_, abc.z * inv_scale_, o_.octaves);
        return ramp_even(0.5 + 0.5 * std::sin(kTwoPi * (abc.z * inv_period_ + o_.turbulence * T)));
      }
      case SliceFunction::rock: {
        const double F = noise_->fbm(abc.x * inv_scale_, abc.y * inv_scale_, abc.z * inv_scale_, o_.octaves);
        return ramp_even(clamp01(0.5 + 0.5 * F));
      }
      case SliceFunction::custom: {
        std::size_t index = 0, stride = 1;
        for (int i = 0; i < 3; ++i) {
          const int n = o_.lookup_dims[static_cast<std::size_t>(i)];
          const double t = clamp01((abc[i] - frame_.lo[i]) * inv_extent_[i]);
          const auto cell = std::min(static_cast<std::size_t>(t * n), static_cast<std::size_t>(n - 1));
          index += cell * stride;
          stride *= static_cast<std::size_t>(n);
        }
        return o_.lookup_colors[index];
      }
    }
    return o_.color;
  }

 private:
  Rgba8 ramp_stops(double t) const {
    const std::vector<RampStop>& s = o_.ramp;
    if (t < s.front().position) return s.front().color;
    if (t >= s.back().position) return s.back().color;
    std::size_t i = 0;
    while (i + 1 < s.size() && s[i + 1].position <= t) ++i;
    // s[i].position <= t < s[i + 1].position
    return mix(s[i].color, s[i + 1].color, (t - s[i].position) / (s[i + 1].position - s[i].position));
  }

  // ramp(colours, t): n colours spread evenly over [0, 1].
  Rgba8 ramp_even(double t) const {
    const std::vector<Rgba8>& c = o_.noise_colors;
    const double s = t * static_cast<double>(c.size() - 1);
    const std::size_t i = std::min(static_cast<std::size_t>(s), c.size() - 2);
    return mix(c[i], c[i + 1], s - static_cast<double>(i));
  }

  const SliceOptions& o_;
  const SliceFrame& frame_;
  glm::dvec3 inv_extent_{0.0};
  double inv_cell_ = 1.0, inv_scale_ = 1.0, inv_period_ = 1.0;
  std::optional<detail::PerlinNoise> noise_;
};

}  // namespace detail

glm::dvec3 SliceFrame::coordinates(const glm::dvec3& p) const {
  const glm::dvec3 d = p - origin;
  return {d.x * u.x + d.y * u.y + d.z * u.z, d.x * v.x + d.y * v.y + d.z * v.z, d.x * w.x + d.y * w.y + d.z * w.z};
}

SliceFrame make_slice_frame(const Mesh& mesh, const glm::dvec3& axis) {
  check_axis(axis);
  SliceFrame f;
  // Scale first so that tiny or huge axes normalize without under/overflow.
  const double m = std::max({std::abs(axis.x), std::abs(axis.y), std::abs(axis.z)});
  const glm::dvec3 a = axis / m;
  f.w = a / std::sqrt(a.x * a.x + a.y * a.y + a.z * a.z);
  int least = 0;
  for (int i = 1; i < 3; ++i)
    if (std::abs(f.w[i]) < std::abs(f.w[least])) least = i;
  glm::dvec3 e(0.0);
  e[least] = 1.0;
  const auto cross = [](const glm::dvec3& p, const glm::dvec3& q) {
    return glm::dvec3(p.y * q.z - p.z * q.y, p.z * q.x - p.x * q.z, p.x * q.y - p.y * q.x);
  };
  const glm::dvec3 c = cross(f.w, e);
  f.u = c / std::sqrt(c.x * c.x + c.y * c.y + c.z * c.z);
  f.v = cross(f.w, f.u);
  f.origin = bounds(mesh).center();
  if (mesh.triangles.empty()) return f;
  f.lo = glm::dvec3(std::numeric_limits<double>::infinity());
  f.hi = -f.lo;
  for (const auto& t : mesh.triangles)
    for (const std::uint32_t index : t) {
      const glm::dvec3 q = f.coordinates(glm::dvec3(mesh.vertices[index]));
      f.lo = glm::min(f.lo, q);
      f.hi = glm::max(f.hi, q);
    }
  return f;
}

void validate(const SliceOptions& o) {
  check_axis(o.axis);
  switch (o.function) {
    case SliceFunction::single_color: check_alpha(o.color, "color"); break;
    case SliceFunction::color_ramp: {
      if (o.ramp.size() < 2)
        bad("color_ramp needs at least 2 ramp stops (position in [0, 1] and colour), got " +
            std::to_string(o.ramp.size()));
      for (std::size_t i = 0; i < o.ramp.size(); ++i) {
        const std::string field = "ramp[" + std::to_string(i) + "]";
        const double p = o.ramp[i].position;
        if (!(p >= 0.0 && p <= 1.0)) bad(field + ".position must be in [0, 1], got " + std::to_string(p));
        if (i > 0 && p < o.ramp[i - 1].position)
          bad(field + ".position " + std::to_string(p) + " is below the previous stop's " +
              std::to_string(o.ramp[i - 1].position) + "; stops must be in non-decreasing order");
        check_alpha(o.ramp[i].color, field + ".color");
      }
      break;
    }
    case SliceFunction::interpolated_colors:
      for (std::size_t i = 0; i < 4; ++i) check_alpha(o.corners[i], "corners[" + std::to_string(i) + "]");
      break;
    case SliceFunction::checker:
      check_size(o.checker_size, "checker_size", "the edge of a checker cell");
      for (std::size_t i = 0; i < 2; ++i) check_alpha(o.checker_colors[i], "checker_colors[" + std::to_string(i) + "]");
      break;
    case SliceFunction::wood:
    case SliceFunction::marble:
    case SliceFunction::rock:
      check_size(o.noise_scale, "noise_scale", "the feature size of the noise");
      if (o.octaves < 1 || o.octaves > 16) bad("octaves must be 1..16, got " + std::to_string(o.octaves));
      if (o.function != SliceFunction::rock) {
        check_size(o.period, "period", o.function == SliceFunction::wood ? "the spacing of the rings"
                                                                           : "the period of the bands");
        if (!(std::isfinite(o.turbulence) && o.turbulence >= 0.0))
          bad("turbulence must be a finite number >= 0 (how far the noise moves rings and bands, in periods), got " +
              std::to_string(o.turbulence));
      }
      if (o.noise_colors.size() < 2 || o.noise_colors.size() > 3)
        bad(std::string(to_string(o.function)) + " needs 2 or 3 noise_colors, got " +
            std::to_string(o.noise_colors.size()));
      for (std::size_t i = 0; i < o.noise_colors.size(); ++i)
        check_alpha(o.noise_colors[i], "noise_colors[" + std::to_string(i) + "]");
      break;
    case SliceFunction::custom: {
      std::size_t cells = 1;
      for (int n : o.lookup_dims) {
        if (n < 1 || n > 64) bad("lookup dims must be 1..64 cells per axis, got " + std::to_string(n));
        cells *= static_cast<std::size_t>(n);
      }
      if (o.lookup_colors.size() != cells)
        bad("lookup colors must hold nx * ny * nz = " + std::to_string(cells) + " colours (x fastest), got " +
            std::to_string(o.lookup_colors.size()));
      for (std::size_t i = 0; i < cells; ++i) check_alpha(o.lookup_colors[i], "lookup colors[" + std::to_string(i) + "]");
      break;
    }
    default: bad("unknown slice function " + std::to_string(static_cast<int>(o.function)));
  }
}

Rgba8 evaluate_slice(const SliceOptions& options, const SliceFrame& frame, const glm::dvec3& model_point) {
  validate(options);
  return detail::SliceShader(options, frame).shade(frame.coordinates(model_point));
}

SliceColours::SliceColours(const SliceOptions& options, const SliceFrame& frame, const Grid& grid)
    : options_(options), frame_(frame), grid_(grid) {
  validate(options_);
  // Along a row the centre moves by voxel_size along x: the frame
  // coordinates by voxel_size * (u.x, v.x, w.x).
  step_ = grid_.voxel_size * glm::dvec3(frame_.u.x, frame_.v.x, frame_.w.x);
  shader_ = std::make_unique<const detail::SliceShader>(options_, frame_);
}

SliceColours::~SliceColours() = default;

glm::dvec3 SliceColours::row_start(std::int64_t j, std::int64_t k) const {
  return frame_.coordinates(grid_.center(0, j, k));
}

Rgba8 SliceColours::along_row(const glm::dvec3& start, std::int64_t i) const {
  const double x = static_cast<double>(i);
  return shader_->shade({start.x + x * step_.x, start.y + x * step_.y, start.z + x * step_.z});
}

DenseVolume<Rgba8> voxelize_slice(const Mesh& mesh, const Grid& grid, const SliceOptions& options,
                                  JobControl* control) {
  validate(options);
  const SliceColours colours(options, make_slice_frame(mesh, options.axis), grid);

  // The solid takes the first half of the caller's share of the bar, the
  // colours the second.
  const BitVolume solid = [&] {
    const NestedSpan first_half(control, 0.0, 0.5);
    return voxelize(mesh, grid, {VoxelMode::solid, options.inside, options.threads}, control);
  }();
  const NestedSpan second_half(control, 0.5, 1.0);

  const std::int64_t nx = grid.dims.x, ny = grid.dims.y, nz = grid.dims.z;
  if (grid.voxel_count() == 0) return DenseVolume<Rgba8>(grid);
  const int threads = options.threads > 0 ? options.threads : default_thread_count();
  const std::int64_t grain = std::max<std::int64_t>(1, nz / (threads * 8));
  // Calls visit(j, i) for each filled voxel (i, j, k) of slab k, in order.
  const auto for_each_filled = [&solid, ny](std::int64_t k, const auto& visit) {
    for (std::int64_t j = 0; j < ny; ++j) {
      const std::uint64_t* row = solid.row(j, k);
      for (std::int64_t word = 0; word < solid.row_words(); ++word)
        for (std::uint64_t bits = row[word]; bits != 0; bits &= bits - 1)
          visit(j, word * 64 + std::countr_zero(bits));
    }
  };

  std::atomic<std::int64_t> slabs_done{0};
  // The colours go straight into the result: on huge pages
  // (voxd/volume_memory.h) its allocation no longer costs a second of page
  // faults that would be worth overlapping with the colouring.
  DenseVolume<Rgba8> out(grid);
  parallel_for(0, nz, grain, threads, [&](std::int64_t k0, std::int64_t k1) {
    for (std::int64_t k = k0; k < k1; ++k) {
      if (control) control->check_cancelled();
      Rgba8* slab = out.slab(k);
      std::int64_t row_j = -1;
      glm::dvec3 start(0.0);
      for_each_filled(k, [&](std::int64_t j, std::int64_t i) {
        if (j != row_j) {
          row_j = j;
          start = colours.row_start(j, k);
        }
        slab[j * nx + i] = colours.along_row(start, i);
      });
      const std::int64_t done = slabs_done.fetch_add(1, std::memory_order_relaxed) + 1;
      if (control) control->set_progress(static_cast<double>(done) / static_cast<double>(nz));
    }
  });
  return out;
}

}  // namespace voxd
