#include "voxd/analysis/sdf_render.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>

#include "voxd/analysis/analysis_images.h"
#include "voxd/byte_sink.h"
#include "voxd/error.h"
#include "voxd/encode/number_text.h"
#include "voxd/parallel.h"

namespace voxd {
namespace {

constexpr double kLattice = 16.0;  // samples per voxel along a ray: every sample lies on this lattice
constexpr double kNear = 1.0;      // voxels: closer to the surface, the march takes every lattice point
constexpr int kBisections = 24;
constexpr std::int64_t kMaxPixels = std::int64_t{1} << 26;  // about 3 GB of per-pixel results
constexpr float kAmbient = 0.2f, kDiffuse = 0.7f, kSpecular = 0.3f;
constexpr int kShininess = 24;

glm::dvec3 axis_vector(int axis, bool positive) {
  glm::dvec3 v(0.0);
  v[axis] = positive ? 1.0 : -1.0;
  return v;
}

std::string signed_axis(int axis, bool positive) { return std::string(positive ? "+" : "-") + "xyz"[axis]; }

// The field in voxels, inside negative, at a point in index coordinates
// (voxel (i, j, k)'s centre at (i, j, k)).
class Field {
 public:
  Field(const DenseVolume<float>& sdf, double scale) : v_(sdf.values().data()), n_(sdf.grid().dims), scale_(scale) {
    sign_ = scale < 0 ? -1.0 : 1.0;
  }

  double value(const glm::dvec3& p) const {
    Corners c = corners(p);
    return scale_ * trilinear(c, [&](std::int64_t i, std::int64_t j, std::int64_t k) { return at(i, j, k); });
  }

  // Trilinear interpolation of the central-difference gradients at the 8
  // centres around p, in the field's orientation (outward), not normalised.
  glm::dvec3 gradient(const glm::dvec3& p) const {
    Corners c = corners(p);
    glm::dvec3 g;
    for (int a = 0; a < 3; ++a) {
      g[a] = trilinear(c, [&](std::int64_t i, std::int64_t j, std::int64_t k) { return difference(a, i, j, k); });
    }
    return sign_ * g;
  }

 private:
  struct Corners {
    std::int64_t lo[3], hi[3];
    double f[3];
  };

  Corners corners(const glm::dvec3& p) const {
    Corners c;
    for (int a = 0; a < 3; ++a) {
      const std::int64_t n = n_[a];
      const double x = std::clamp(p[a], 0.0, static_cast<double>(n - 1));
      const std::int64_t i0 = std::min<std::int64_t>(static_cast<std::int64_t>(x), std::max<std::int64_t>(n - 2, 0));
      c.lo[a] = i0;
      c.hi[a] = std::min<std::int64_t>(i0 + 1, n - 1);
      c.f[a] = x - static_cast<double>(i0);
    }
    return c;
  }

  template <class Get>
  static double trilinear(const Corners& c, Get get) {
    auto lerp = [](double a, double b, double f) { return a + f * (b - a); };
    const double x00 = lerp(get(c.lo[0], c.lo[1], c.lo[2]), get(c.hi[0], c.lo[1], c.lo[2]), c.f[0]);
    const double x10 = lerp(get(c.lo[0], c.hi[1], c.lo[2]), get(c.hi[0], c.hi[1], c.lo[2]), c.f[0]);
    const double x01 = lerp(get(c.lo[0], c.lo[1], c.hi[2]), get(c.hi[0], c.lo[1], c.hi[2]), c.f[0]);
    const double x11 = lerp(get(c.lo[0], c.hi[1], c.hi[2]), get(c.hi[0], c.hi[1], c.hi[2]), c.f[0]);
    return lerp(lerp(x00, x10, c.f[1]), lerp(x01, x11, c.f[1]), c.f[2]);
  }

  double at(std::int64_t i, std::int64_t j, std::int64_t k) const {
    return static_cast<double>(v_[static_cast<std::size_t>(i + n_.x * (j + n_.y * k))]);
  }

  // Central difference along axis a at centre (i, j, k); one-sided on the grid's faces.
  double difference(int a, std::int64_t i, std::int64_t j, std::int64_t k) const {
    const std::int64_t n = n_[a];
    if (n < 2) return 0.0;
    std::int64_t m[3] = {i, j, k}, q[3] = {i, j, k};
    const std::int64_t x = m[a];
    m[a] = std::max<std::int64_t>(x - 1, 0);
    q[a] = std::min<std::int64_t>(x + 1, n - 1);
    return (at(q[0], q[1], q[2]) - at(m[0], m[1], m[2])) / static_cast<double>(q[a] - m[a]);
  }

  const float* v_;
  glm::i64vec3 n_;
  double scale_;
  double sign_;
};

void check_input(const SdfRenderInput& input, int pixels_per_voxel) {
  if (!input.sdf) throw Error(ErrorCode::invalid_argument, "sdf render: no signed distance field given");
  const glm::i64vec3 d = input.sdf->grid().dims;
  if (d.x <= 0 || d.y <= 0 || d.z <= 0) {
    throw Error(ErrorCode::invalid_argument, "sdf render: the field's grid is empty (" + std::to_string(d.x) + " x " +
                                                 std::to_string(d.y) + " x " + std::to_string(d.z) + " voxels)");
  }
  if (input.sdf->values().size() != input.sdf->grid().voxel_count()) {
    throw Error(ErrorCode::invalid_argument, "sdf render: the field holds " + std::to_string(input.sdf->values().size()) +
                                                 " values for " + std::to_string(input.sdf->grid().voxel_count()) + " voxels");
  }
  if (!(input.units_per_voxel > 0.0) || !std::isfinite(input.units_per_voxel)) {
    throw Error(ErrorCode::invalid_argument,
                "sdf render: units_per_voxel must be a positive finite number, got " + number_text(input.units_per_voxel));
  }
  if (pixels_per_voxel < 1 || pixels_per_voxel > 8) {
    throw Error(ErrorCode::invalid_argument,
                "sdf render: pixels per voxel must be 1 to 8, got " + std::to_string(pixels_per_voxel));
  }
}

}  // namespace

SdfRenderInput sdf_render_input(const DenseVolume<float>& sdf, const SdfOptions& options) {
  SdfRenderInput in;
  in.sdf = &sdf;
  in.inside_negative = options.sign == SignConvention::inside_negative;
  in.units_per_voxel = options.model_units ? sdf.grid().voxel_size : 1.0;
  in.unit = options.model_units ? "model units" : "voxel";
  return in;
}

SdfRenderImage render_sdf(const SdfRenderInput& input, View view, int threads, int pixels_per_voxel) {
  const ViewBasis basis = view_basis(view);  // checks the axis
  check_input(input, pixels_per_voxel);
  const Grid& grid = input.sdf->grid();
  const glm::i64vec3 dims = grid.dims;
  const std::int64_t s = pixels_per_voxel;
  const std::int64_t n_right = dims[basis.right_axis], n_up = dims[basis.up_axis], n_depth = dims[view.axis];
  const std::int64_t width = n_right * s, height = n_up * s;
  if (width > kMaxPixels / height) {
    throw Error(ErrorCode::limit_exceeded, "sdf render: the image would be " + std::to_string(width) + " x " +
                                               std::to_string(height) + " pixels, over the limit of " +
                                               std::to_string(kMaxPixels));
  }

  SdfRenderImage img;
  img.width = static_cast<int>(width);
  img.height = static_cast<int>(height);
  img.pixels_per_voxel = pixels_per_voxel;
  const std::size_t pixels = static_cast<std::size_t>(width * height);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  img.hit.assign(pixels, glm::dvec3(nan));
  img.normal.assign(pixels, glm::vec3(0.0f));
  img.shade.assign(pixels, 0.0f);
  img.specular.assign(pixels, 0.0f);
  img.image.width = img.width;
  img.image.height = img.height;
  img.image.pixels.assign(pixels * 3, 255);

  const Field field(*input.sdf, (input.inside_negative ? 1.0 : -1.0) / input.units_per_voxel);
  const glm::dvec3 forward = axis_vector(view.axis, !view.from_positive);
  const glm::dvec3 right = axis_vector(basis.right_axis, basis.right_positive);
  const glm::dvec3 up = axis_vector(basis.up_axis, basis.up_positive);
  const glm::vec3 light = glm::normalize(glm::vec3(-forward + 0.5 * up - 0.35 * right));
  const glm::vec3 towards_camera = glm::vec3(-forward);
  const double inv_s = 1.0 / static_cast<double>(s);

  parallel_for(0, height, 4, threads, [&](std::int64_t r0, std::int64_t r1) {
    for (std::int64_t r = r0; r < r1; ++r) {
      const double v = (static_cast<double>(r) + 0.5) * inv_s;  // voxels from the top edge
      const double along_up = basis.up_positive ? static_cast<double>(n_up) - 0.5 - v : v - 0.5;
      for (std::int64_t c = 0; c < width; ++c) {
        const double u = (static_cast<double>(c) + 0.5) * inv_s;
        const double along_right = basis.right_positive ? u - 0.5 : static_cast<double>(n_right) - 0.5 - u;
        glm::dvec3 origin;
        origin[basis.right_axis] = along_right;
        origin[basis.up_axis] = along_up;
        origin[view.axis] = view.from_positive ? static_cast<double>(n_depth) - 0.5 : -0.5;
        auto at = [&](double t) { return origin + t * forward; };

        // Sphere tracing on the lattice of 1/16 voxel along the ray (see the
        // header); t_hit < 0: miss. m = the lattice index of the sample.
        double t_hit = -1.0;
        bool entry = false;
        auto sample = [&](std::int64_t m) { return field.value(at(static_cast<double>(m) / kLattice)); };
        const std::int64_t m_end = n_depth * static_cast<std::int64_t>(kLattice);
        std::int64_t m = 0;
        double d = sample(0);
        if (d <= 0.0) {
          t_hit = 0.0;
          entry = true;
        } else {
          std::int64_t m_prev = 0;
          while (m < m_end) {
            m_prev = m;
            // NaN counts as outside; a huge or infinite value ends the ray.
            const std::int64_t step =
                !(d >= kNear) ? 1 : static_cast<std::int64_t>(std::floor(std::min(d * kLattice, static_cast<double>(m_end))));
            m = std::min(m + step, m_end);
            d = sample(m);
            if (!(d <= 0.0)) continue;
            // The crossing lies in the lattice step before m (stepping back
            // over lattice points a long step overshot, never behind m_prev).
            std::int64_t lo_m = m - 1;
            double d_lo = sample(lo_m);
            double d_hi = d;
            while (d_lo <= 0.0 && lo_m > m_prev) {
              d_hi = d_lo;
              --lo_m;
              d_lo = sample(lo_m);
            }
            double lo = static_cast<double>(lo_m) / kLattice, hi = static_cast<double>(lo_m + 1) / kLattice;
            for (int b = 0; b < kBisections; ++b) {
              const double mid = 0.5 * (lo + hi);
              const double dm = field.value(at(mid));
              if (dm <= 0.0) {
                hi = mid;
                d_hi = dm;
              } else {
                lo = mid;
                d_lo = dm;
              }
            }
            t_hit = d_lo > 0.0 ? lo + (hi - lo) * (d_lo / (d_lo - d_hi)) : lo;
            t_hit = std::clamp(t_hit, lo, hi);
            break;
          }
        }
        if (t_hit < 0.0) continue;

        const std::size_t p = static_cast<std::size_t>(r * width + c);
        const glm::dvec3 q = at(t_hit);
        glm::vec3 n = towards_camera;
        if (!entry) {
          const glm::dvec3 g = field.gradient(q);
          const double len = glm::length(g);
          if (len > 1e-12) n = glm::vec3(g / len);
        }
        const float nl = glm::dot(n, light);
        const float shade = kAmbient + kDiffuse * std::max(0.0f, nl);
        float spec = 0.0f;
        if (nl > 0.0f) {
          const glm::vec3 reflected = 2.0f * nl * n - light;
          const float rv = std::max(0.0f, glm::dot(reflected, towards_camera));
          float power = 1.0f;
          for (int e = 0; e < kShininess; ++e) power *= rv;
          spec = kSpecular * power;
        }
        img.hit[p] = grid.origin + (q + 0.5) * grid.voxel_size;
        img.normal[p] = n;
        img.shade[p] = shade;
        img.specular[p] = spec;
        const Rgb base = kPreviewPartColour;
        std::uint8_t* px = &img.image.pixels[3 * p];
        const std::uint8_t rgb[3] = {base.r, base.g, base.b};
        for (int ch = 0; ch < 3; ++ch) {
          const float value = static_cast<float>(rgb[ch]) * shade + 255.0f * spec;
          px[ch] = static_cast<std::uint8_t>(std::lround(std::min(value, 255.0f)));
        }
      }
    }
  });
  return img;
}

namespace {

// The render `factor` times smaller along each side (rounded up), each pixel
// its block's nearest hit (ties: the first in row order), as
// shrink_preview does for a voxel preview.
RgbImage shrink_render(const SdfRenderImage& render, View view, int factor) {
  RgbImage out;
  out.width = (render.width + factor - 1) / factor;
  out.height = (render.height + factor - 1) / factor;
  out.pixels.assign(static_cast<std::size_t>(out.width) * static_cast<std::size_t>(out.height) * 3, 255);
  const double towards_camera = view.from_positive ? 1.0 : -1.0;
  for (int row = 0; row < out.height; ++row)
    for (int col = 0; col < out.width; ++col) {
      std::size_t best = SIZE_MAX;
      double best_nearness = 0.0;
      for (int r = row * factor; r < std::min(render.height, (row + 1) * factor); ++r)
        for (int c = col * factor; c < std::min(render.width, (col + 1) * factor); ++c) {
          const std::size_t p = static_cast<std::size_t>(r) * static_cast<std::size_t>(render.width) + static_cast<std::size_t>(c);
          const double at = render.hit[p][view.axis];
          if (std::isnan(at)) continue;
          if (best == SIZE_MAX || at * towards_camera > best_nearness) {
            best = p;
            best_nearness = at * towards_camera;
          }
        }
      if (best == SIZE_MAX) continue;
      std::copy_n(&render.image.pixels[3 * best], 3,
                  &out.pixels[3 * (static_cast<std::size_t>(row) * static_cast<std::size_t>(out.width) + static_cast<std::size_t>(col))]);
    }
  return out;
}

}  // namespace

std::vector<std::uint8_t> sdf_preview_png(const SdfRenderInput& input, View view, std::vector<PngText> text, int threads,
                                          int pixels_per_voxel, int max_side) {
  const SdfRenderImage render = render_sdf(input, view, threads, pixels_per_voxel);
  const int factor = shrink_factor(render.width, render.height, max_side);
  const ViewBasis basis = view_basis(view);
  std::vector<PngText> chunks = {
      {"voxd:view", to_string(view)},
      {"voxd:right", signed_axis(basis.right_axis, basis.right_positive)},
      {"voxd:up", signed_axis(basis.up_axis, basis.up_positive)},
      {"voxd:voxel_size", number_text(input.sdf->grid().voxel_size * factor / pixels_per_voxel) + " model units per pixel"},
      {"voxd:pixels_per_voxel", std::to_string(pixels_per_voxel)},
      {"voxd:lighting",
       "Orthographic view of the zero level set of the trilinearly interpolated signed distance field, normals from "
       "its central-difference gradient, Phong lighting from the viewer's upper left: colour = part colour x (0.2 + "
       "0.7 max(0, n.L)) + white x 0.3 max(0, R.V)^24."},
      {"voxd:render", "sdf sphere tracing"}};
  if (factor > 1)
    chunks.push_back({"voxd:shrunk", "each pixel a block of " + std::to_string(factor) + " x " + std::to_string(factor) +
                                         " rendered pixels, showing its nearest hit"});
  chunks.insert(chunks.end(), text.begin(), text.end());
  VectorSink out;
  write_png_rgb8(factor > 1 ? shrink_render(render, view, factor) : render.image, chunks, out);
  return std::move(out.data);
}

}  // namespace voxd
