// Direct rendering of signed distance fields (voxd/analysis/sdf_render.h), checked on
// analytic fields: a sphere (silhouette, hit points on the sphere, normals
// against the analytic normal, where the highlight sits), a box (flat faces
// with exact normals), both sign conventions and both units (same bits), a
// field clamped to a narrow band (same image), thread counts (same bits), the
// view orientation against the voxel preview, and the PNG as an independent
// reader (tests/tools/read_png.py) decodes it.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <numbers>
#include <string>
#include <unistd.h>

#include <glm/geometric.hpp>

#include "support/run_process.h"
#include "support/test_checks.h"
#include "support/test_meshes.h"
#include "voxd/analysis/analysis_images.h"
#include "voxd/error.h"
#include "voxd/analysis/preview.h"
#include "voxd/analysis/sdf_render.h"

namespace voxd {
namespace {

using nlohmann::json;
using test::code_of;
using test::decode_png;
using test::kViews;
using test::view_of;
using test::ViewCase;

glm::dvec3 forward(const ViewCase& v) { return test::forward<glm::dvec3>(v); }
glm::dvec3 light(const ViewCase& v) { return test::light<glm::dvec3>(v); }
double degrees(glm::dvec3 a, glm::dvec3 b) {
  return std::acos(std::clamp(glm::dot(glm::normalize(a), glm::normalize(b)), -1.0, 1.0)) * 180.0 / std::numbers::pi;
}

// Model coordinates of pixel (c, r)'s ray along the right and up axes (the
// depth coordinate is left 0): pixel centres, s pixels per voxel, row 0 at the
// top.
glm::dvec3 ray_point(const ViewCase& v, const Grid& g, int s, std::int64_t c, std::int64_t r) {
  const double n_right = static_cast<double>(g.dims[v.right_axis]), n_up = static_cast<double>(g.dims[v.up_axis]);
  const double along_right = (static_cast<double>(c) + 0.5) / s;  // voxels from the image's left edge
  const double along_down = (static_cast<double>(r) + 0.5) / s;
  glm::dvec3 p(0.0);
  p[v.right_axis] = g.origin[v.right_axis] + (v.right_sign > 0 ? along_right : n_right - along_right) * g.voxel_size;
  p[v.up_axis] = g.origin[v.up_axis] + (v.up_sign > 0 ? n_up - along_down : along_down) * g.voxel_size;
  return p;
}

// Analytic fields at the voxel centres, in the given convention and units,
// optionally clamped to +-band voxels as a narrow-band field is.
DenseVolume<float> field(const Grid& g, const std::function<double(glm::dvec3)>& distance, bool inside_negative,
                         bool voxel_units, double band_voxels = std::numeric_limits<double>::infinity()) {
  DenseVolume<float> f(g);
  for (std::int64_t k = 0; k < g.dims.z; ++k)
    for (std::int64_t j = 0; j < g.dims.y; ++j)
      for (std::int64_t i = 0; i < g.dims.x; ++i) {
        double d = distance(g.center(i, j, k)) / g.voxel_size;  // voxels
        d = std::clamp(d, -band_voxels, band_voxels);
        if (!voxel_units) d *= g.voxel_size;
        f.at(i, j, k) = static_cast<float>(inside_negative ? d : -d);
      }
  return f;
}

SdfRenderInput input_of(const DenseVolume<float>& f, bool inside_negative, bool voxel_units) {
  return SdfRenderInput{&f, inside_negative, voxel_units ? 1.0 : f.grid().voxel_size, voxel_units ? "voxel" : "model units"};
}

// A non-cubic grid off the origin with a power-of-two voxel size (so the two
// units give the same floats up to an exact factor).
Grid sphere_grid() { return test::make_grid({40, 36, 32}, {1.5, -2.0, 0.25}, 0.5); }
const glm::dvec3 kCentre{1.5 + 20.3 * 0.5, -2.0 + 17.8 * 0.5, 0.25 + 16.1 * 0.5};
constexpr double kRadius = 6.0;  // 12 voxels
double sphere_distance(glm::dvec3 p) { return glm::length(p - kCentre) - kRadius; }

bool same_bits(const SdfRenderImage& a, const SdfRenderImage& b) {
  return a.width == b.width && a.height == b.height && a.image.pixels == b.image.pixels &&
         std::memcmp(a.hit.data(), b.hit.data(), a.hit.size() * sizeof(glm::dvec3)) == 0 &&
         std::memcmp(a.normal.data(), b.normal.data(), a.normal.size() * sizeof(glm::vec3)) == 0 && a.shade == b.shade &&
         a.specular == b.specular && a.hit.size() == b.hit.size() && a.normal.size() == b.normal.size();
}

TEST(SdfRender, SphereSilhouetteHitsAndNormalsInEveryView) {
  const Grid g = sphere_grid();
  const DenseVolume<float> f = field(g, sphere_distance, true, false);
  for (const int s : {1, 3}) {
    for (const ViewCase& v : kViews) {
      SCOPED_TRACE(std::string(v.name) + " pixels per voxel " + std::to_string(s));
      const SdfRenderImage img = render_sdf(input_of(f, true, false), view_of(v), 2, s);
      ASSERT_EQ(img.width, g.dims[v.right_axis] * s);
      ASSERT_EQ(img.height, g.dims[v.up_axis] * s);
      ASSERT_EQ(img.pixels_per_voxel, s);
      int hits = 0, misses = 0;
      double worst_distance = 0.0, worst_angle = 0.0;
      for (int r = 0; r < img.height; ++r)
        for (int c = 0; c < img.width; ++c) {
          const std::size_t p = static_cast<std::size_t>(r) * img.width + c;
          const glm::dvec3 ray = ray_point(v, g, s, c, r);
          glm::dvec3 lateral = kCentre - ray;
          lateral[v.axis] = 0.0;
          const double rho = glm::length(lateral);
          const bool hit = !std::isnan(img.hit[p].x);
          if (rho < kRadius - g.voxel_size) {
            EXPECT_TRUE(hit) << c << "," << r;
          }
          if (rho > kRadius + g.voxel_size) {
            EXPECT_FALSE(hit) << c << "," << r;
          }
          const std::uint8_t* px = &img.image.pixels[3 * p];
          if (!hit) {
            ++misses;
            EXPECT_TRUE(std::isnan(img.hit[p].y) && std::isnan(img.hit[p].z));
            EXPECT_EQ(img.normal[p], glm::vec3(0.0f));
            EXPECT_EQ(img.shade[p], 0.0f);
            EXPECT_TRUE(px[0] == 255 && px[1] == 255 && px[2] == 255) << "background is white";
            continue;
          }
          ++hits;
          // On the ray, on the sphere, on the camera's side of it.
          EXPECT_NEAR(img.hit[p][v.right_axis], ray[v.right_axis], 1e-9);
          EXPECT_NEAR(img.hit[p][v.up_axis], ray[v.up_axis], 1e-9);
          worst_distance = std::max(worst_distance, std::abs(glm::length(img.hit[p] - kCentre) - kRadius) / g.voxel_size);
          if (rho < kRadius - g.voxel_size) {
            EXPECT_GT(glm::dot(img.hit[p] - kCentre, -forward(v)), 0.0) << "the near side";
          }
          EXPECT_NEAR(glm::length(glm::dvec3(img.normal[p])), 1.0, 1e-5);
          worst_angle = std::max(worst_angle, degrees(glm::dvec3(img.normal[p]), img.hit[p] - kCentre));
          // The shade and colour as documented.
          const double nl = glm::dot(glm::dvec3(img.normal[p]), light(v));
          EXPECT_NEAR(img.shade[p], 0.2 + 0.7 * std::max(0.0, nl), 1e-5);
          const Rgb part = kPreviewPartColour;
          const double rgb[3] = {double(part.r), double(part.g), double(part.b)};
          for (int ch = 0; ch < 3; ++ch) {
            EXPECT_NEAR(px[ch], std::min(255.0, rgb[ch] * img.shade[p] + 255.0 * img.specular[p]), 0.51);
          }
        }
      EXPECT_LT(worst_distance, 0.05) << "hit points off the sphere, in voxels (0.02 measured)";
      EXPECT_LT(worst_angle, 1.0) << "normals off the analytic normal, in degrees (0.09 measured)";
      // The silhouette's area is pi r^2 to within the one-voxel band.
      const double expected = std::numbers::pi * kRadius * kRadius / (g.voxel_size * g.voxel_size) * s * s;
      EXPECT_NEAR(hits, expected, 2.0 * std::numbers::pi * (kRadius / g.voxel_size) * s * s);
      EXPECT_GT(misses, 0);
    }
  }
}

TEST(SdfRender, HighlightsSitWhereTheNormalMeetsTheLight) {
  const Grid g = sphere_grid();
  const DenseVolume<float> f = field(g, sphere_distance, true, true);
  for (const ViewCase& v : kViews) {
    SCOPED_TRACE(v.name);
    const SdfRenderImage img = render_sdf(input_of(f, true, true), view_of(v), 0, 4);
    std::size_t brightest = 0, shiniest = 0;
    for (std::size_t p = 0; p < img.shade.size(); ++p) {
      if (img.shade[p] > img.shade[brightest]) brightest = p;
      if (img.specular[p] > img.specular[shiniest]) shiniest = p;
    }
    // Diffuse peak at n = L, the Phong highlight at n = the half vector of L and the view.
    EXPECT_LT(degrees(img.hit[brightest] - kCentre, light(v)), 2.0);
    EXPECT_NEAR(img.shade[brightest], 0.9, 1e-3);
    EXPECT_LT(degrees(img.hit[shiniest] - kCentre, light(v) - forward(v)), 2.0);
    EXPECT_NEAR(img.specular[shiniest], 0.3, 1e-2);
    // And the brightest pixel of the picture lies between the two.
    std::size_t lightest = 0;
    auto sum = [&](std::size_t p) {
      const std::uint8_t* px = &img.image.pixels[3 * p];
      return std::isnan(img.hit[p].x) ? -1 : px[0] + px[1] + px[2];
    };
    for (std::size_t p = 0; p < img.shade.size(); ++p)
      if (sum(p) > sum(lightest)) lightest = p;
    const glm::dvec3 n = img.hit[lightest] - kCentre;
    EXPECT_LT(degrees(n, light(v)) + degrees(n, light(v) - forward(v)), degrees(light(v), light(v) - forward(v)) + 3.0);
  }
}

TEST(SdfRender, ConventionsAndUnitsGiveTheSameBits) {
  const Grid g = sphere_grid();
  for (const ViewCase& v : kViews) {
    SCOPED_TRACE(v.name);
    const DenseVolume<float> reference = field(g, sphere_distance, true, false);
    const SdfRenderImage want = render_sdf(input_of(reference, true, false), view_of(v), 2);
    for (const bool inside_negative : {true, false})
      for (const bool voxels : {true, false}) {
        const DenseVolume<float> f = field(g, sphere_distance, inside_negative, voxels);
        EXPECT_TRUE(same_bits(render_sdf(input_of(f, inside_negative, voxels), view_of(v), 2), want))
            << "inside_negative " << inside_negative << " voxels " << voxels;
      }
  }
  // Reading a field with the wrong convention renders the complement: every ray starts inside.
  const DenseVolume<float> f = field(g, sphere_distance, true, false);
  const SdfRenderImage wrong = render_sdf(input_of(f, false, false), View{2, true}, 2);
  for (std::size_t p = 0; p < wrong.hit.size(); ++p) {
    ASSERT_FALSE(std::isnan(wrong.hit[p].x));
    EXPECT_EQ(wrong.normal[p], glm::vec3(0.0f, 0.0f, 1.0f));
    EXPECT_DOUBLE_EQ(wrong.hit[p].z, g.origin.z + static_cast<double>(g.dims.z) * g.voxel_size);  // the grid's top face
  }
}

TEST(SdfRender, ClampedBandRendersLikeTheFullField) {
  const Grid g = sphere_grid();
  for (const bool inside_negative : {true, false}) {
    const DenseVolume<float> full = field(g, sphere_distance, inside_negative, false);
    const DenseVolume<float> band = field(g, sphere_distance, inside_negative, false, 3.0);
    for (const ViewCase& v : kViews) {
      SCOPED_TRACE(v.name);
      for (const int s : {1, 2}) {
        const SdfRenderImage a = render_sdf(input_of(full, inside_negative, false), view_of(v), 2, s);
        const SdfRenderImage b = render_sdf(input_of(band, inside_negative, false), view_of(v), 2, s);
        EXPECT_TRUE(same_bits(a, b)) << "pixels per voxel " << s;
      }
    }
  }
}

TEST(SdfRender, NaNAndHugeValuesAreSafe) {
  const Grid g = sphere_grid();
  const DenseVolume<float> band = field(g, sphere_distance, true, true, 3.0);
  DenseVolume<float> holes = band, huge = band;
  for (std::size_t p = 0; p < band.values().size(); ++p) {
    if (band.values()[p] >= 3.0f) {
      holes.values()[p] = std::numeric_limits<float>::quiet_NaN();  // counts as outside
      huge.values()[p] = std::numeric_limits<float>::max();           // no surface within reach: the ray ends
    }
  }
  const SdfRenderImage want = render_sdf(input_of(band, true, true), View{1, false}, 2);
  EXPECT_TRUE(same_bits(render_sdf(input_of(holes, true, true), View{1, false}, 2), want));
  const SdfRenderImage ended = render_sdf(input_of(huge, true, true), View{1, false}, 2);
  for (const glm::dvec3& h : ended.hit) EXPECT_TRUE(std::isnan(h.x));
}

TEST(SdfRender, ResultDoesNotDependOnTheThreadCount) {
  const Grid g = sphere_grid();
  const DenseVolume<float> f = field(g, sphere_distance, true, false, 3.0);
  for (const ViewCase& v : {kViews[0], kViews[3], kViews[4]}) {
    const SdfRenderImage one = render_sdf(input_of(f, true, false), view_of(v), 1, 2);
    for (const int threads : {2, 3, 7, 0}) {
      EXPECT_TRUE(same_bits(one, render_sdf(input_of(f, true, false), view_of(v), threads, 2))) << v.name << " " << threads;
    }
  }
}

TEST(SdfRender, BoxFacesHaveExactConstantNormals) {
  const Grid g = test::make_grid({30, 26, 24}, {-1.0, 2.0, 0.5}, 0.25);
  // Faces between voxel centres, off the lattice.
  const glm::dvec3 lo = g.origin + glm::dvec3(5.3, 4.7, 6.2) * g.voxel_size;
  const glm::dvec3 hi = g.origin + glm::dvec3(24.6, 20.1, 17.4) * g.voxel_size;
  const glm::dvec3 mid = 0.5 * (lo + hi), half = 0.5 * (hi - lo);
  auto box = [&](glm::dvec3 p) {
    const glm::dvec3 q = glm::abs(p - mid) - half;
    return glm::length(glm::max(q, glm::dvec3(0.0))) + std::min(std::max(q.x, std::max(q.y, q.z)), 0.0);
  };
  const DenseVolume<float> f = field(g, box, true, false, 3.0);
  for (const ViewCase& v : kViews) {
    SCOPED_TRACE(v.name);
    const SdfRenderImage img = render_sdf(input_of(f, true, false), view_of(v), 2);
    const glm::vec3 facing = glm::vec3(-forward(v));
    const double face = v.from_positive ? hi[v.axis] : lo[v.axis];
    int face_pixels = 0;
    float face_shade = -1.0f;
    for (int r = 0; r < img.height; ++r)
      for (int c = 0; c < img.width; ++c) {
        const std::size_t p = static_cast<std::size_t>(r) * img.width + c;
        const glm::dvec3 ray = ray_point(v, g, 1, c, r);
        // Lateral distance inside the face's edges, in voxels.
        const double inset = std::min({ray[v.right_axis] - lo[v.right_axis], hi[v.right_axis] - ray[v.right_axis],
                                       ray[v.up_axis] - lo[v.up_axis], hi[v.up_axis] - ray[v.up_axis]}) /
                             g.voxel_size;
        const bool hit = !std::isnan(img.hit[p].x);
        if (inset < -1.0) {
          EXPECT_FALSE(hit);
        }
        if (inset < 3.0) continue;
        ASSERT_TRUE(hit);
        ++face_pixels;
        EXPECT_EQ(img.normal[p], facing) << c << "," << r;
        EXPECT_NEAR(img.hit[p][v.axis], face, 1e-5 * g.voxel_size);
        if (face_shade < 0) face_shade = img.shade[p];
        EXPECT_EQ(img.shade[p], face_shade);
      }
    EXPECT_GT(face_pixels, 30);
    EXPECT_NEAR(face_shade, 0.2 + 0.7 * glm::dot(glm::dvec3(facing), light(v)), 1e-6);
  }
}

TEST(SdfRender, LinesUpWithTheVoxelPreview) {
  const Grid g = sphere_grid();
  // An off-centre part (a box and the sphere) so a flipped or transposed image shows.
  auto shape = [](glm::dvec3 p) {
    const glm::dvec3 q = glm::abs(p - glm::dvec3(4.1, 0.6, 2.6)) - glm::dvec3(2.0, 2.5, 1.5);
    const double box = glm::length(glm::max(q, glm::dvec3(0.0))) + std::min(std::max(q.x, std::max(q.y, q.z)), 0.0);
    return std::min(box, sphere_distance(p));
  };
  const DenseVolume<float> f = field(g, shape, true, true);
  BitVolume solid(g);
  for (std::int64_t k = 0; k < g.dims.z; ++k)
    for (std::int64_t j = 0; j < g.dims.y; ++j)
      for (std::int64_t i = 0; i < g.dims.x; ++i) solid.set(i, j, k, f.at(i, j, k) < 0.0f);
  for (const ViewCase& v : kViews) {
    SCOPED_TRACE(v.name);
    const SdfRenderImage img = render_sdf(input_of(f, true, true), view_of(v), 2);
    const PreviewImage preview = render_preview(solid, view_of(v), 2);
    ASSERT_EQ(img.width, preview.width);
    ASSERT_EQ(img.height, preview.height);
    // With one ray per voxel column through the centres, both see the same
    // columns, except where the field only grazes zero along the column.
    int hits = 0, grazing = 0;
    for (int r = 0; r < img.height; ++r)
      for (int c = 0; c < img.width; ++c) {
        const std::size_t p = static_cast<std::size_t>(r) * img.width + c;
        const glm::dvec3 ray = ray_point(v, g, 1, c, r);
        std::int64_t ijk[3];
        ijk[v.right_axis] = static_cast<std::int64_t>(std::floor((ray[v.right_axis] - g.origin[v.right_axis]) / g.voxel_size));
        ijk[v.up_axis] = static_cast<std::int64_t>(std::floor((ray[v.up_axis] - g.origin[v.up_axis]) / g.voxel_size));
        float lowest = std::numeric_limits<float>::infinity();
        for (ijk[v.axis] = 0; ijk[v.axis] < g.dims[v.axis]; ++ijk[v.axis]) lowest = std::min(lowest, f.at(ijk[0], ijk[1], ijk[2]));
        const bool hit = !std::isnan(img.hit[p].x);
        hits += hit;
        EXPECT_EQ(preview.voxel[p] >= 0, lowest < 0.0f) << "the test's column lookup";
        if (lowest > -0.2f * g.voxel_size && lowest <= 0.0f) {
          ++grazing;
          continue;
        }
        EXPECT_EQ(hit, preview.voxel[p] >= 0) << c << "," << r << " column minimum " << lowest;
      }
    EXPECT_GT(hits, 100);
    EXPECT_LT(grazing, hits / 10);
  }
}

TEST(SdfRender, PartCutByTheGridIsSeenFromItsCutFace) {
  const Grid g = test::make_grid({6, 5, 4});
  DenseVolume<float> f(g, -2.0f);  // inside everywhere
  const SdfRenderImage img = render_sdf(SdfRenderInput{&f, true, 1.0, "voxel"}, View{0, false}, 1);
  for (std::size_t p = 0; p < img.hit.size(); ++p) {
    EXPECT_DOUBLE_EQ(img.hit[p].x, 0.0);
    EXPECT_EQ(img.normal[p], glm::vec3(-1.0f, 0.0f, 0.0f));
  }
  // And outside everywhere: nothing.
  DenseVolume<float> empty(g, 3.0f);
  const SdfRenderImage none = render_sdf(SdfRenderInput{&empty, true, 1.0, "voxel"}, View{2, true}, 1);
  for (const glm::dvec3& h : none.hit) EXPECT_TRUE(std::isnan(h.x));
}

TEST(SdfRender, InputFromSdfOptions) {
  const Grid g = test::make_grid({3, 3, 3}, glm::dvec3(0.0), 0.125);
  const DenseVolume<float> f(g, 1.0f);
  SdfOptions o;
  o.sign = SignConvention::inside_positive;
  o.model_units = true;
  SdfRenderInput in = sdf_render_input(f, o);
  EXPECT_EQ(in.sdf, &f);
  EXPECT_FALSE(in.inside_negative);
  EXPECT_EQ(in.units_per_voxel, 0.125);
  EXPECT_EQ(in.unit, "model units");
  o.sign = SignConvention::inside_negative;
  o.model_units = false;
  in = sdf_render_input(f, o);
  EXPECT_TRUE(in.inside_negative);
  EXPECT_EQ(in.units_per_voxel, 1.0);
  EXPECT_EQ(in.unit, "voxel");
}

TEST(SdfRender, PngDecodesWithItsMetadata) {
  const Grid g = sphere_grid();
  const DenseVolume<float> f = field(g, sphere_distance, false, false);
  const SdfRenderInput in = input_of(f, false, false);
  for (const ViewCase& v : {kViews[1], kViews[4]}) {
    const SdfRenderImage img = render_sdf(in, view_of(v), 0, 2);
    const json png = decode_png(sdf_preview_png(in, view_of(v), {{"voxd:job", "abc"}}, 0, 2));
    ASSERT_EQ(png["width"], img.width);
    ASSERT_EQ(png["height"], img.height);
    EXPECT_EQ(png["bit_depth"], 8);
    EXPECT_EQ(png["color_type"], 2);
    EXPECT_EQ(png["pixels"].get<std::vector<std::uint8_t>>(), img.image.pixels);
    EXPECT_EQ(png["text"]["voxd:view"], v.name);
    EXPECT_EQ(png["text"]["voxd:right"], std::string(v.right_sign > 0 ? "+" : "-") + "xyz"[v.right_axis]);
    EXPECT_EQ(png["text"]["voxd:up"], std::string(v.up_sign > 0 ? "+" : "-") + "xyz"[v.up_axis]);
    EXPECT_EQ(png["text"]["voxd:voxel_size"], "0.25 model units per pixel");
    EXPECT_EQ(png["text"]["voxd:pixels_per_voxel"], "2");
    EXPECT_EQ(png["text"]["voxd:render"], "sdf sphere tracing");
    EXPECT_NE(png["text"]["voxd:lighting"].get<std::string>().find("Phong"), std::string::npos);
    EXPECT_EQ(png["text"]["voxd:job"], "abc");
  }
  // Issue #39: shrunk to a size, each pixel its block's nearest hit (found
  // here from the render's hits), and the PNG says so.
  for (const ViewCase& v : {kViews[1], kViews[4]}) {
    SCOPED_TRACE(v.name);
    const SdfRenderImage img = render_sdf(in, view_of(v), 0, 2);
    const int factor = 3;
    const int side = (std::max(img.width, img.height) + factor - 1) / factor;
    const json png = decode_png(sdf_preview_png(in, view_of(v), {}, 0, 2, side));
    ASSERT_EQ(png["width"], (img.width + factor - 1) / factor);
    ASSERT_EQ(png["height"], (img.height + factor - 1) / factor);
    EXPECT_EQ(png["text"]["voxd:voxel_size"], "0.75 model units per pixel");
    EXPECT_EQ(png["text"]["voxd:shrunk"], "each pixel a block of 3 x 3 rendered pixels, showing its nearest hit");
    const auto pixels = png["pixels"].get<std::vector<std::uint8_t>>();
    const int w = png["width"];
    for (int r = 0; r < png["height"].get<int>(); ++r)
      for (int c = 0; c < w; ++c) {
        int best = -1;
        for (int br = r * factor; br < std::min(img.height, (r + 1) * factor); ++br)
          for (int bc = c * factor; bc < std::min(img.width, (c + 1) * factor); ++bc) {
            const int p = br * img.width + bc;
            const double at = img.hit[static_cast<std::size_t>(p)][v.axis];
            if (std::isnan(at)) continue;
            const double best_at = best < 0 ? 0.0 : img.hit[static_cast<std::size_t>(best)][v.axis];
            if (best < 0 || (v.from_positive ? at > best_at : at < best_at)) best = p;
          }
        for (int ch = 0; ch < 3; ++ch)
          EXPECT_EQ(pixels[static_cast<std::size_t>(3 * (r * w + c) + ch)],
                    best < 0 ? 255 : img.image.pixels[static_cast<std::size_t>(3 * best + ch)])
              << c << "," << r;
      }
  }
  if (const char* dir = std::getenv("VOXD_SDF_RENDER_PNG_DIR")) {  // for looking at the picture
    test::write_file(std::string(dir) + "/sdf_sphere_px.png", sdf_preview_png(in, View{0, true}, {}, 0, 4));
  }
}

TEST(SdfRender, BadInputsAreInvalidArguments) {
  const Grid g = test::make_grid({4, 4, 4});
  const DenseVolume<float> f(g, 1.0f);
  std::string msg;
  EXPECT_EQ(code_of([&] { render_sdf(SdfRenderInput{}, View{2, true}); }, &msg), ErrorCode::invalid_argument);
  EXPECT_NE(msg.find("no signed distance field"), std::string::npos) << msg;
  EXPECT_EQ(code_of([&] { render_sdf(SdfRenderInput{&f, true, 0.0, "voxel"}, View{2, true}); }, &msg),
            ErrorCode::invalid_argument);
  EXPECT_NE(msg.find("units_per_voxel must be a positive finite number, got 0"), std::string::npos) << msg;
  EXPECT_EQ(code_of([&] { render_sdf(SdfRenderInput{&f, true, std::nan(""), "voxel"}, View{2, true}); }),
            ErrorCode::invalid_argument);
  for (const int s : {0, 9, -1}) {
    EXPECT_EQ(code_of([&] { render_sdf(SdfRenderInput{&f, true, 1.0, "voxel"}, View{2, true}, 1, s); }, &msg),
              ErrorCode::invalid_argument);
    EXPECT_NE(msg.find("pixels per voxel must be 1 to 8, got " + std::to_string(s)), std::string::npos) << msg;
  }
  EXPECT_EQ(code_of([&] { sdf_preview_png(SdfRenderInput{&f, true, 1.0, "voxel"}, View{3, true}); }, &msg),
            ErrorCode::invalid_argument);
  EXPECT_NE(msg.find("got 3"), std::string::npos) << msg;
  const DenseVolume<float> flat(test::make_grid({4, 0, 4}));
  EXPECT_EQ(code_of([&] { render_sdf(SdfRenderInput{&flat, true, 1.0, "voxel"}, View{2, true}); }, &msg),
            ErrorCode::invalid_argument);
  EXPECT_NE(msg.find("empty (4 x 0 x 4 voxels)"), std::string::npos) << msg;
  const DenseVolume<float> huge_grid_view(test::make_grid({1, 1, 1}));
  EXPECT_NO_THROW(render_sdf(SdfRenderInput{&huge_grid_view, true, 1.0, "voxel"}, View{1, false}, 1, 8));
}

}  // namespace
}  // namespace voxd
