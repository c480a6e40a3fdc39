// Multi-valued solid voxelization by slice functions (after Liao): the solid,
// then the slice function at the centre of each of its voxels. Formulas and
// parameters in voxd/voxelize/slice_functions.h.
#include "voxd/voxelize/slice_functions.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <glm/common.hpp>

#include "voxd/detail/slice_gpu.h"
#include "voxd/error.h"
#include "voxd/parallel.h"
#include "voxelize/slice_device.h"
#include "voxelize/splitmix.h"

namespace voxd {
namespace {

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
}  // namespace

namespace detail {

std::unique_ptr<const SliceShading> make_slice_shading(const SliceOptions& o, const SliceFrame& frame,
                                                       const Grid& grid) {
  auto shading = std::make_unique<SliceShading>();
  SliceShadeParams& p = shading->params;
  const auto colour = [](const Rgba8& c) { return ShadeColour{c.r, c.g, c.b, c.a}; };
  p.function = static_cast<int>(o.function);
  p.color = colour(o.color);
  for (std::size_t i = 0; i < 4; ++i) p.corners[i] = colour(o.corners[i]);
  for (std::size_t i = 0; i < 2; ++i) p.checker[i] = colour(o.checker_colors[i]);
  // Validated: 2 or 3 noise colours, at least 2 ramp stops, a full lookup,
  // for the function that uses them.
  p.noise_count = static_cast<int>(std::min<std::size_t>(o.noise_colors.size(), 3));
  for (int i = 0; i < p.noise_count; ++i) p.noise_colors[i] = colour(o.noise_colors[static_cast<std::size_t>(i)]);
  if (o.function == SliceFunction::color_ramp)
    for (const RampStop& stop : o.ramp) shading->ramp.push_back({stop.position, colour(stop.color)});
  if (o.function == SliceFunction::custom)
    for (const Rgba8& c : o.lookup_colors) shading->lookup.push_back(colour(c));
  p.ramp = shading->ramp.data();
  p.ramp_count = static_cast<int>(shading->ramp.size());
  p.lookup = shading->lookup.data();
  for (int i = 0; i < 3; ++i) p.lookup_dims[i] = o.lookup_dims[static_cast<std::size_t>(i)];
  const glm::dvec3 extent = frame.hi - frame.lo;
  for (int i = 0; i < 3; ++i) {
    p.lo[i] = frame.lo[i];
    p.inv_extent[i] = extent[i] > 0.0 ? 1.0 / extent[i] : 0.0;
  }
  p.inv_cell = 1.0 / o.checker_size;
  p.inv_scale = 1.0 / o.noise_scale;
  p.inv_period = 1.0 / o.period;
  p.turbulence = o.turbulence;
  p.octaves = o.octaves;
  // The noise's permutation: 0..255 shuffled by Fisher-Yates with
  // splitmix64(seed), twice over so p[i + 1] never wraps.
  std::array<std::uint8_t, 256> perm;
  for (int i = 0; i < 256; ++i) perm[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(i);
  std::uint64_t state = o.seed;
  for (std::uint64_t i = 255; i >= 1; --i) std::swap(perm[i], perm[splitmix64(state) % (i + 1)]);
  shading->perm.resize(512);
  for (std::size_t i = 0; i < 512; ++i) shading->perm[i] = perm[i & 255];
  p.perm = shading->perm.data();

  SliceVoxelFrame& f = shading->frame;
  for (int i = 0; i < 3; ++i) {
    f.grid_origin[i] = grid.origin[i];
    f.frame_origin[i] = frame.origin[i];
    f.u[i] = frame.u[i];
    f.v[i] = frame.v[i];
    f.w[i] = frame.w[i];
  }
  f.voxel_size = grid.voxel_size;
  // Along a row the centre moves by voxel_size along x: the frame
  // coordinates by voxel_size * (u.x, v.x, w.x).
  f.step[0] = grid.voxel_size * frame.u.x;
  f.step[1] = grid.voxel_size * frame.v.x;
  f.step[2] = grid.voxel_size * frame.w.x;
  return shading;
}

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

namespace {
Rgba8 rgba(const detail::ShadeColour& c) { return {c.r, c.g, c.b, c.a}; }
}  // namespace

Rgba8 evaluate_slice(const SliceOptions& options, const SliceFrame& frame, const glm::dvec3& model_point) {
  validate(options);
  const auto shading = detail::make_slice_shading(options, frame, Grid{});
  const glm::dvec3 abc = frame.coordinates(model_point);
  return rgba(detail::slice_shade(shading->params, abc.x, abc.y, abc.z));
}

SliceColours::SliceColours(const SliceOptions& options, const SliceFrame& frame, const Grid& grid) : grid_(grid) {
  validate(options);
  shading_ = detail::make_slice_shading(options, frame, grid);
}

SliceColours::~SliceColours() = default;

glm::dvec3 SliceColours::row_start(std::int64_t j, std::int64_t k) const {
  double start[3];
  detail::slice_row_start(shading_->frame, j, k, start);
  return {start[0], start[1], start[2]};
}

Rgba8 SliceColours::along_row(const glm::dvec3& start, std::int64_t i) const {
  const double s[3] = {start.x, start.y, start.z};
  return rgba(detail::slice_along_row(shading_->params, shading_->frame, s, i));
}

ComputeDevice slice_device_for(const SliceOptions& options, const Grid& grid) {
  if (options.device != ComputeDevice::automatic) return options.device;
  const bool noise = options.function == SliceFunction::wood || options.function == SliceFunction::marble ||
                     options.function == SliceFunction::rock;
  return noise && grid.voxel_count() >= (std::uint64_t{1} << 21) && cuda_unavailable_reason().empty()
             ? ComputeDevice::cuda
             : ComputeDevice::cpu;
}

DenseVolume<Rgba8> voxelize_slice(const Mesh& mesh, const Grid& grid, const SliceOptions& options,
                                  JobControl* control, SliceRunReport* report) {
  validate(options);
  if (slice_device_for(options, grid) == ComputeDevice::cuda) {
    if (options.device == ComputeDevice::cuda)
      return detail::voxelize_slice_on(detail::SliceBackend::cuda, mesh, grid, options, control, report);
    // automatic: a GPU that cannot take the work (its memory taken by
    // others, a CUDA failure) leaves it to the CPU, whose bytes are the
    // same; the report says where it ran. Cancellation is not a failure.
    try {
      return detail::voxelize_slice_on(detail::SliceBackend::cuda, mesh, grid, options, control, report);
    } catch (const Error& e) {
      if (e.code() == ErrorCode::cancelled) throw;
    } catch (const std::runtime_error&) {
    }
  }
  if (report) *report = SliceRunReport{};
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
