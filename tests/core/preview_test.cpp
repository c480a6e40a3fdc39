// Shaded preview: which voxel each pixel shows (against the box bounds and a
// bit-by-bit ray walk), the image orientation of every view, normals and
// shading on shapes with known normals (box faces, a sphere), and the PNG
// as an independent reader (tests/tools/read_png.py) decodes it.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <unistd.h>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "support/run_process.h"
#include "support/test_checks.h"
#include "support/test_meshes.h"
#include "voxd/analysis/analysis_images.h"
#include "voxd/encode/colour_map.h"
#include "voxd/error.h"
#include "voxd/analysis/preview.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd {
namespace {

using nlohmann::json;
using test::code_of;
using test::decode_png;
using test::kViews;
using test::view_of;
using test::ViewCase;

glm::vec3 unit(int axis, int sign) { return test::unit<glm::vec3>(axis, sign); }
glm::vec3 forward(const ViewCase& v) { return test::forward<glm::vec3>(v); }
glm::vec3 light(const ViewCase& v) { return test::light<glm::vec3>(v); }
// Grid coordinates of the voxel a pixel's ray runs along, as the table says.
std::int64_t right_coord(const ViewCase& v, const glm::i64vec3& dims, std::int64_t c) {
  return v.right_sign > 0 ? c : dims[v.right_axis] - 1 - c;
}
std::int64_t up_coord(const ViewCase& v, const glm::i64vec3& dims, std::int64_t r) {
  return v.up_sign > 0 ? dims[v.up_axis] - 1 - r : r;
}

Grid unit_grid(std::int64_t nx, std::int64_t ny, std::int64_t nz, double voxel_size = 1.0) {
  Grid g;
  g.voxel_size = voxel_size;
  g.dims = {nx, ny, nz};
  return g;
}

// Voxels lo..hi (inclusive) set directly, so the expected answer does not go
// through a voxelizer.
void fill_box(BitVolume& v, glm::i64vec3 lo, glm::i64vec3 hi) {
  for (std::int64_t k = lo.z; k <= hi.z; ++k)
    for (std::int64_t j = lo.y; j <= hi.y; ++j)
      for (std::int64_t i = lo.x; i <= hi.x; ++i) v.set(i, j, k, true);
}

glm::i64vec3 voxel_coords(const BitVolume& v, std::int64_t index) {
  const auto d = v.grid().dims;
  return {index % d.x, (index / d.x) % d.y, index / (d.x * d.y)};
}

std::size_t at(const PreviewImage& img, std::int64_t c, std::int64_t r) { return static_cast<std::size_t>(r * img.width + c); }

Rgb png_pixel(const json& png, std::int64_t x, std::int64_t y) {
  const std::size_t p = (static_cast<std::size_t>(y) * png["width"].get<std::size_t>() + static_cast<std::size_t>(x)) * 3;
  return {png["pixels"][p].get<std::uint8_t>(), png["pixels"][p + 1].get<std::uint8_t>(), png["pixels"][p + 2].get<std::uint8_t>()};
}

Rgb shaded(Rgb c, float shade) {
  auto s = [&](std::uint8_t v) { return static_cast<std::uint8_t>(std::lround(v * shade)); };
  return {s(c.r), s(c.g), s(c.b)};
}

TEST(PreviewView, ParseAndToStringRoundTrip) {
  for (const ViewCase& v : kViews) {
    const auto parsed = parse_view(v.name);
    ASSERT_TRUE(parsed) << v.name;
    EXPECT_EQ(parsed->axis, v.axis) << v.name;
    EXPECT_EQ(parsed->from_positive, v.from_positive) << v.name;
    EXPECT_EQ(to_string(*parsed), v.name);
  }
  for (const char* bare : {"x", "y", "z"}) {
    const auto parsed = parse_view(bare);
    ASSERT_TRUE(parsed) << bare;
    EXPECT_TRUE(parsed->from_positive);
    EXPECT_EQ(to_string(*parsed), std::string("+") + bare);
  }
  for (const char* bad : {"", "+", "-", "w", "+w", "X", "+Z", "xx", "++x", "+-x", " x", "x ", "+x ", "+xy", "*z", "z+", "0"}) {
    EXPECT_FALSE(parse_view(bad)) << '"' << bad << '"';
  }
  EXPECT_EQ(code_of([] { to_string(View{3, true}); }), ErrorCode::invalid_argument);
}

TEST(PreviewView, BasesMatchTheTableAndAreRightHanded) {
  for (const ViewCase& v : kViews) {
    const ViewBasis b = view_basis(view_of(v));
    EXPECT_EQ(b.right_axis, v.right_axis) << v.name;
    EXPECT_EQ(b.right_positive, v.right_sign > 0) << v.name;
    EXPECT_EQ(b.up_axis, v.up_axis) << v.name;
    EXPECT_EQ(b.up_positive, v.up_sign > 0) << v.name;
    // right x up points back at the camera: what a camera sees, never its mirror image.
    const glm::vec3 toward_camera = glm::cross(unit(b.right_axis, b.right_positive ? 1 : -1), unit(b.up_axis, b.up_positive ? 1 : -1));
    EXPECT_EQ(toward_camera, -forward(v)) << v.name;
  }
  BitVolume v(unit_grid(4, 4, 4));
  for (int axis : {-1, 3}) {
    EXPECT_EQ(code_of([&] { view_basis(View{axis, true}); }), ErrorCode::invalid_argument);
    EXPECT_EQ(code_of([&] { render_preview(v, View{axis, false}); }), ErrorCode::invalid_argument);
    EXPECT_EQ(code_of([&] { preview_png(v, View{axis, true}, nullptr); }), ErrorCode::invalid_argument);
  }
}

TEST(PreviewBox, FootprintAndVisibleFaceFromEachView) {
  // Off-centre box, different extent on every axis, x across a word boundary.
  const glm::i64vec3 lo{50, 5, 2}, hi{77, 9, 10};
  BitVolume vol(unit_grid(90, 16, 13));
  fill_box(vol, lo, hi);
  const auto dims = vol.grid().dims;
  for (const ViewCase& v : kViews) {
    SCOPED_TRACE(v.name);
    const PreviewImage img = render_preview(vol, view_of(v), 2);
    ASSERT_EQ(img.width, dims[v.right_axis]);
    ASSERT_EQ(img.height, dims[v.up_axis]);
    ASSERT_EQ(img.voxel.size(), static_cast<std::size_t>(img.width * img.height));
    std::int64_t hits = 0;
    for (std::int64_t r = 0; r < img.height; ++r) {
      for (std::int64_t c = 0; c < img.width; ++c) {
        glm::i64vec3 want{0};
        want[v.right_axis] = right_coord(v, dims, c);
        want[v.up_axis] = up_coord(v, dims, r);
        want[v.axis] = v.from_positive ? hi[v.axis] : lo[v.axis];  // the face towards the camera
        const bool inside = want[v.right_axis] >= lo[v.right_axis] && want[v.right_axis] <= hi[v.right_axis] &&
                            want[v.up_axis] >= lo[v.up_axis] && want[v.up_axis] <= hi[v.up_axis];
        const std::int64_t got = img.voxel[at(img, c, r)];
        if (!inside) {
          EXPECT_EQ(got, -1) << c << "," << r;
          EXPECT_EQ(img.shade[at(img, c, r)], 0.0f);
          EXPECT_EQ(img.normal[at(img, c, r)], glm::vec3(0.0f));
          continue;
        }
        ++hits;
        EXPECT_EQ(got, want.x + dims.x * (want.y + dims.y * want.z)) << c << "," << r;
      }
    }
    EXPECT_EQ(hits, (hi[v.right_axis] - lo[v.right_axis] + 1) * (hi[v.up_axis] - lo[v.up_axis] + 1));
  }
}

TEST(PreviewBox, FlatFaceHasExactNormalAndConstantShade) {
  const glm::i64vec3 lo{3, 4, 2}, hi{20, 15, 12};
  BitVolume vol(unit_grid(24, 19, 16));
  fill_box(vol, lo, hi);
  const auto dims = vol.grid().dims;
  for (const ViewCase& v : kViews) {
    SCOPED_TRACE(v.name);
    const PreviewImage img = render_preview(vol, view_of(v));
    const glm::vec3 f = forward(v);
    // Every visible voxel lies on the facing face, so all are at the nearest
    // depth: depth cue 1 everywhere.
    const float face_shade = 0.2f + 0.8f * glm::dot(-f, light(v));
    const std::int64_t c_lo = v.right_sign > 0 ? lo[v.right_axis] : dims[v.right_axis] - 1 - hi[v.right_axis];
    const std::int64_t c_hi = c_lo + hi[v.right_axis] - lo[v.right_axis];
    const std::int64_t r_lo = v.up_sign > 0 ? dims[v.up_axis] - 1 - hi[v.up_axis] : lo[v.up_axis];
    const std::int64_t r_hi = r_lo + hi[v.up_axis] - lo[v.up_axis];
    for (std::int64_t r = r_lo; r <= r_hi; ++r) {
      for (std::int64_t c = c_lo; c <= c_hi; ++c) {
        const std::size_t p = at(img, c, r);
        ASSERT_GE(img.voxel[p], 0);
        EXPECT_NEAR(glm::length(img.normal[p]), 1.0f, 1e-5f);
        // Two pixels in from the outline the whole 3x3 window sees only the flat face.
        if (r - r_lo < 2 || r_hi - r < 2 || c - c_lo < 2 || c_hi - c < 2) continue;
        EXPECT_NEAR(glm::distance(img.normal[p], -f), 0.0f, 1e-6f) << c << "," << r;
        EXPECT_NEAR(img.shade[p], face_shade, 1e-5f) << c << "," << r;
      }
    }
    // On the outline the normal leans outwards (the side faces' empty neighbours count).
    const glm::vec3 left_edge = img.normal[at(img, c_lo, (r_lo + r_hi) / 2)];
    const glm::vec3 top_edge = img.normal[at(img, (c_lo + c_hi) / 2, r_lo)];
    EXPECT_GT(glm::dot(left_edge, -unit(v.right_axis, v.right_sign)), 0.2f);
    EXPECT_GT(glm::dot(top_edge, unit(v.up_axis, v.up_sign)), 0.2f);
    EXPECT_GT(glm::dot(left_edge, -f), 0.5f);
    // One pixel in, the voxel's own normal is -f; smoothing with the outline tilts it.
    EXPECT_GT(glm::dot(img.normal[at(img, c_lo + 1, (r_lo + r_hi) / 2)], -unit(v.right_axis, v.right_sign)), 0.05f);
  }
}

TEST(PreviewBox, DepthCueAndSmoothingFollowDepth) {
  // Two blocks side by side seen from +z: tops at k = 11 (nearest) and k = 5
  // (farthest), same flat normal.
  BitVolume tall(unit_grid(30, 12, 14));
  fill_box(tall, {1, 1, 0}, {12, 10, 11});
  BitVolume both = tall.clone();
  fill_box(both, {13, 1, 0}, {28, 10, 5});
  const PreviewImage img = render_preview(both, View{2, true});
  const float flat = 0.2f + 0.8f * glm::dot(glm::vec3(0, 0, 1), light(kViews[0]));
  const std::int64_t mid_row = 12 - 1 - 5;  // j = 5
  EXPECT_NEAR(img.shade[at(img, 6, mid_row)], flat, 1e-5f);
  EXPECT_NEAR(img.shade[at(img, 22, mid_row)], flat * 0.8f, 1e-5f);
  // The tall block's edge (column 12) is 6 voxels above its neighbour in
  // column 13: too far to be averaged with it, so its normals are what they
  // are without the low block (whose voxels are not in its 26-neighbourhood).
  const PreviewImage alone = render_preview(tall, View{2, true});
  for (std::int64_t r = 1; r <= 10; ++r) {
    EXPECT_EQ(img.normal[at(img, 12, r)], alone.normal[at(alone, 12, r)]) << r;
    EXPECT_GT(img.normal[at(img, 12, r)].x, 0.2f) << r;  // leans over the edge
  }
}

TEST(PreviewOrientation, AsymmetricObjectIsNotMirrored) {
  // A base plate with a tower at large x and small y standing up to large z.
  BitVolume vol(unit_grid(24, 20, 16));
  fill_box(vol, {2, 2, 2}, {21, 17, 5});
  fill_box(vol, {16, 2, 6}, {21, 7, 13});
  for (const ViewCase& v : kViews) {
    SCOPED_TRACE(v.name);
    const PreviewImage img = render_preview(vol, view_of(v));
    int large_x = 0, large_z = 0, tower = 0;
    for (std::int64_t r = 0; r < img.height; ++r) {
      for (std::int64_t c = 0; c < img.width; ++c) {
        const std::int64_t index = img.voxel[at(img, c, r)];
        if (index < 0) continue;
        const glm::i64vec3 p = voxel_coords(vol, index);
        const bool right_half = 2 * c >= img.width, upper_half = 2 * r < img.height;
        if (v.axis != 0 && p.x >= 16) {
          // +z and -y have right = +x; -z and +y look the other way along x.
          ++large_x;
          EXPECT_EQ(right_half, v.name == std::string("+z") || v.name == std::string("-y")) << c << "," << r;
        }
        if (v.axis != 2 && p.z >= 8) {
          ++large_z;
          EXPECT_TRUE(upper_half) << c << "," << r;
        }
        if (p.z >= 6 && v.axis == 0) {
          // The tower stands at small y: left for +x (right = +y), right for -x.
          ++tower;
          EXPECT_EQ(right_half, !v.from_positive) << c << "," << r;
        }
      }
    }
    EXPECT_EQ(large_x > 0, v.axis != 0);
    EXPECT_EQ(large_z > 0, v.axis != 2);
    EXPECT_EQ(tower > 0, v.axis == 0);
  }
}

TEST(PreviewVisibility, MatchesABitByBitRayWalk) {
  // Random blobs in a volume three words wide: the word-parallel searches
  // against the plainest possible walk from the camera side.
  const Grid g = unit_grid(150, 23, 19);
  BitVolume vol(g);
  std::mt19937 rng(11);
  for (int n = 0; n < 40; ++n) {
    const glm::i64vec3 lo{rng() % 150, rng() % 23, rng() % 19};
    const glm::i64vec3 size{1 + rng() % 30, 1 + rng() % 6, 1 + rng() % 6};
    fill_box(vol, lo, glm::min(lo + size - std::int64_t{1}, g.dims - std::int64_t{1}));
  }
  for (std::int64_t k = 0; k < g.dims.z; ++k)  // and a sprinkling of single voxels
    for (std::int64_t j = 0; j < g.dims.y; ++j) vol.set(rng() % 150, j, k, rng() % 3 == 0);
  for (const ViewCase& v : kViews) {
    SCOPED_TRACE(v.name);
    const PreviewImage img = render_preview(vol, view_of(v), 3);
    for (std::int64_t r = 0; r < img.height; ++r) {
      for (std::int64_t c = 0; c < img.width; ++c) {
        glm::i64vec3 p{0};
        p[v.right_axis] = right_coord(v, g.dims, c);
        p[v.up_axis] = up_coord(v, g.dims, r);
        std::int64_t want = -1;
        for (std::int64_t s = 0; s < g.dims[v.axis] && want < 0; ++s) {
          p[v.axis] = v.from_positive ? g.dims[v.axis] - 1 - s : s;
          if (vol.get(p.x, p.y, p.z)) want = p.x + g.dims.x * (p.y + g.dims.y * p.z);
        }
        ASSERT_EQ(img.voxel[at(img, c, r)], want) << c << "," << r;
        if (want >= 0) {
          EXPECT_NEAR(glm::length(img.normal[at(img, c, r)]), 1.0f, 1e-5f);
          EXPECT_GE(img.shade[at(img, c, r)], 0.0f);
          EXPECT_LE(img.shade[at(img, c, r)], 1.0f);
        }
      }
    }
  }
}

TEST(PreviewVisibility, LoneVoxelFacesTheCameraAndEmptyVolumeIsBackground) {
  // All 26 neighbours empty: they cancel, so the normal falls back to -f.
  BitVolume vol(unit_grid(5, 6, 7));
  vol.set(2, 3, 4, true);
  for (const ViewCase& v : kViews) {
    const PreviewImage img = render_preview(vol, view_of(v));
    std::int64_t hits = 0;
    for (std::size_t p = 0; p < img.voxel.size(); ++p) {
      if (img.voxel[p] < 0) continue;
      ++hits;
      EXPECT_EQ(img.normal[p], -forward(v)) << v.name;
      EXPECT_NEAR(img.shade[p], 0.2f + 0.8f * glm::dot(-forward(v), light(v)), 1e-6f) << v.name;
    }
    EXPECT_EQ(hits, 1) << v.name;
  }
  const BitVolume empty(unit_grid(5, 6, 7));
  for (const ViewCase& v : kViews) {
    const PreviewImage img = render_preview(empty, view_of(v));
    EXPECT_EQ(img.width, empty.grid().dims[v.right_axis]);
    EXPECT_EQ(img.height, empty.grid().dims[v.up_axis]);
    EXPECT_EQ(img.voxel, std::vector<std::int64_t>(static_cast<std::size_t>(img.width * img.height), -1)) << v.name;
    EXPECT_EQ(img.shade, std::vector<float>(img.voxel.size(), 0.0f));
    EXPECT_EQ(img.normal, std::vector<glm::vec3>(img.voxel.size(), glm::vec3(0.0f)));
  }
}

TEST(PreviewSphere, NormalsPointOutwardsAndShadeFallsAwayFromTheLight) {
  const double R = 15.0;
  const glm::dvec3 centre{20.0, 20.0, 20.0};
  const BitVolume vol = voxelize(test::make_icosphere(centre, R, 4), unit_grid(40, 40, 40), {});
  for (const ViewCase& v : {kViews[0], kViews[3], kViews[4]}) {
    SCOPED_TRACE(v.name);
    const PreviewImage img = render_preview(vol, view_of(v));
    const glm::vec3 L = light(v);
    // Normals: unit length and close to the true sphere normal at the visible voxel.
    double angle_sum = 0.0;
    int hits = 0;
    std::size_t best = 0;
    for (std::size_t p = 0; p < img.voxel.size(); ++p) {
      if (img.voxel[p] < 0) continue;
      ++hits;
      const glm::i64vec3 q = voxel_coords(vol, img.voxel[p]);
      const glm::vec3 truth = glm::normalize(glm::vec3(vol.grid().center(q.x, q.y, q.z) - centre));
      const float n_len = glm::length(img.normal[p]);
      EXPECT_NEAR(n_len, 1.0f, 1e-5f);
      const double angle = std::acos(std::clamp(glm::dot(img.normal[p], truth) / n_len, -1.0f, 1.0f)) * 180.0 / std::numbers::pi;
      EXPECT_LT(angle, 20.0) << "pixel " << p;
      angle_sum += angle;
      if (glm::dot(img.normal[p], L) > glm::dot(img.normal[best], L) || img.voxel[best] < 0) best = p;
    }
    ASSERT_GT(hits, 500);
    EXPECT_LT(angle_sum / hits, 6.0);
    // The pixel whose normal is closest to L is where the sphere's true normal is L.
    const std::int64_t bc = static_cast<std::int64_t>(best) % img.width, br = static_cast<std::int64_t>(best) / img.width;
    const glm::dvec3 lit = centre + R * glm::dvec3(L);
    glm::i64vec3 lit_voxel = glm::i64vec3(glm::floor(lit));
    const double lit_c = v.right_sign > 0 ? lit_voxel[v.right_axis] : 39 - lit_voxel[v.right_axis];
    const double lit_r = v.up_sign > 0 ? 39 - lit_voxel[v.up_axis] : lit_voxel[v.up_axis];
    EXPECT_LE(std::hypot(bc - lit_c, br - lit_r), 2.0) << bc << "," << br << " vs " << lit_c << "," << lit_r;
    // The brightest pixel is near it, and the shade falls ring by ring away from it.
    std::size_t brightest = 0;
    for (std::size_t p = 0; p < img.shade.size(); ++p) {
      if (img.shade[p] > img.shade[brightest]) brightest = p;
    }
    const std::int64_t mc = static_cast<std::int64_t>(brightest) % img.width, mr = static_cast<std::int64_t>(brightest) / img.width;
    EXPECT_LE(std::hypot(mc - bc, mr - br), 3.0);
    std::vector<double> ring_sum(6, 0.0);  // 4-pixel rings out to the far rim
    std::vector<int> ring_n(6, 0);
    for (std::size_t p = 0; p < img.voxel.size(); ++p) {
      if (img.voxel[p] < 0) continue;
      const double d = std::hypot(static_cast<double>(static_cast<std::int64_t>(p) % img.width - bc),
                                  static_cast<double>(static_cast<std::int64_t>(p) / img.width - br));
      const std::size_t ring = static_cast<std::size_t>(d / 4.0);
      if (ring < ring_sum.size()) {
        ring_sum[ring] += img.shade[p];
        ++ring_n[ring];
      }
    }
    for (std::size_t ring = 1; ring < ring_sum.size(); ++ring) {
      ASSERT_GT(ring_n[ring], 10);
      EXPECT_LT(ring_sum[ring] / ring_n[ring], ring_sum[ring - 1] / ring_n[ring - 1]) << "ring " << ring;
    }
    EXPECT_GT(img.shade[brightest], 0.9f);
    EXPECT_LT(ring_sum.back() / ring_n.back(), 0.3);
  }
}

TEST(PreviewThreads, SameImageOnOneAndSeveralThreads) {
  const Mesh m = test::concat({test::make_icosphere({30, 20, 18}, 12.0, 3), test::make_box({4, 6, 3}, {70, 14, 9}),
                               test::make_torus({50, 24, 20}, 10.0, 3.0, 40, 16)});
  const BitVolume vol = voxelize(m, unit_grid(80, 40, 36), {});
  for (const ViewCase& v : kViews) {
    SCOPED_TRACE(v.name);
    const PreviewImage one = render_preview(vol, view_of(v), 1);
    for (int threads : {2, 5, 0}) {
      const PreviewImage many = render_preview(vol, view_of(v), threads);
      EXPECT_EQ(many.voxel, one.voxel);
      EXPECT_EQ(many.shade, one.shade);
      EXPECT_EQ(many.normal, one.normal);
    }
    EXPECT_EQ(preview_png(vol, view_of(v), nullptr, {}, 1), preview_png(vol, view_of(v), nullptr, {}, 4));
  }
}

TEST(PreviewPng, PlainPreviewDecodesWithTextAndWhiteBackground) {
  BitVolume vol(unit_grid(24, 19, 16, 0.5));
  fill_box(vol, {3, 4, 2}, {20, 15, 12});
  fill_box(vol, {14, 6, 13}, {18, 9, 15});
  for (const ViewCase& v : {kViews[0], kViews[5]}) {
    SCOPED_TRACE(v.name);
    const PreviewImage img = render_preview(vol, view_of(v));
    const json png = decode_png(preview_png(vol, view_of(v), nullptr, {{"voxd:source", "part.stl"}}));
    ASSERT_EQ(png["width"], img.width);
    ASSERT_EQ(png["height"], img.height);
    EXPECT_EQ(png["bit_depth"], 8);
    EXPECT_EQ(png["color_type"], 2);
    const auto& text = png["text"];
    EXPECT_EQ(text["voxd:view"], v.name);
    EXPECT_EQ(text["voxd:right"], std::string(v.right_sign > 0 ? "+" : "-") + "xyz"[v.right_axis]);
    EXPECT_EQ(text["voxd:up"], std::string(v.up_sign > 0 ? "+" : "-") + "xyz"[v.up_axis]);
    EXPECT_EQ(text["voxd:voxel_size"], "0.5 model units per pixel");
    EXPECT_GT(text["voxd:lighting"].get<std::string>().size(), 20u);
    EXPECT_EQ(text["voxd:source"], "part.stl");
    EXPECT_FALSE(text.contains("voxd:legend"));
    for (std::int64_t r = 0; r < img.height; ++r) {
      for (std::int64_t c = 0; c < img.width; ++c) {
        const std::size_t p = at(img, c, r);
        const Rgb want = img.voxel[p] < 0 ? Rgb{255, 255, 255} : shaded(kPreviewPartColour, img.shade[p]);
        EXPECT_EQ(png_pixel(png, c, r), want) << c << "," << r;
      }
    }
  }
}

// Issue #39: a preview of a huge grid is shown at a sensible size. The
// factor is the smallest that fits; each shown pixel is its block's nearest
// visible voxel, found here by walking the block's rays voxel by voxel, so
// a plate one voxel thick seen edge-on stays in view at any factor.
TEST(PreviewShrink, FactorIsTheSmallestThatFits) {
  EXPECT_EQ(shrink_factor(8194, 7918, 2048), 5);
  EXPECT_EQ(shrink_factor(2048, 100, 2048), 1);
  EXPECT_EQ(shrink_factor(2049, 100, 2048), 2);
  EXPECT_EQ(shrink_factor(100, 4097, 2048), 3);
  EXPECT_EQ(shrink_factor(8194, 7918, 0), 1);  // full size
  EXPECT_EQ(code_of([] { shrink_preview(PreviewImage{}, unit_grid(1, 1, 1), View{}, 0); }), ErrorCode::invalid_argument);
}

TEST(PreviewShrink, EachPixelIsItsBlocksNearestVoxelAndThinWallsStay) {
  const Grid g = unit_grid(61, 47, 29);
  BitVolume vol(g);
  std::mt19937 rng(5);
  for (int n = 0; n < 25; ++n) {
    const glm::i64vec3 lo{rng() % 61, rng() % 47, rng() % 29};
    const glm::i64vec3 size{1 + rng() % 12, 1 + rng() % 12, 1 + rng() % 12};
    fill_box(vol, lo, glm::min(lo + size - std::int64_t{1}, g.dims - std::int64_t{1}));
  }
  // Plates one voxel thick, edge-on to some view: x = 50, y = 40, z = 3.
  fill_box(vol, {50, 0, 0}, {50, 46, 28});
  fill_box(vol, {0, 40, 0}, {60, 40, 28});
  fill_box(vol, {0, 0, 3}, {60, 46, 3});
  for (const ViewCase& v : kViews) {
    const PreviewImage full = render_preview(vol, view_of(v), 2);
    for (int factor : {1, 2, 3, 7, 64}) {
      SCOPED_TRACE(std::string(v.name) + ", factor " + std::to_string(factor));
      const PreviewImage small = shrink_preview(full, g, view_of(v), factor);
      ASSERT_EQ(small.width, (full.width + factor - 1) / factor);
      ASSERT_EQ(small.height, (full.height + factor - 1) / factor);
      for (std::int64_t r = 0; r < small.height; ++r)
        for (std::int64_t c = 0; c < small.width; ++c) {
          // The block's rays walked from the camera: the nearest voxel, the
          // first in row order among equals.
          std::int64_t want = -1, want_depth = 0, want_pixel = -1;
          for (std::int64_t br = r * factor; br < std::min<std::int64_t>(full.height, (r + 1) * factor); ++br)
            for (std::int64_t bc = c * factor; bc < std::min<std::int64_t>(full.width, (c + 1) * factor); ++bc) {
              glm::i64vec3 p{0};
              p[v.right_axis] = right_coord(v, g.dims, bc);
              p[v.up_axis] = up_coord(v, g.dims, br);
              for (std::int64_t depth = 0; depth < g.dims[v.axis]; ++depth) {
                p[v.axis] = v.from_positive ? g.dims[v.axis] - 1 - depth : depth;
                if (!vol.get(p.x, p.y, p.z)) continue;
                if (want < 0 || depth < want_depth) {
                  want = p.x + g.dims.x * (p.y + g.dims.y * p.z);
                  want_depth = depth;
                  want_pixel = br * full.width + bc;
                }
                break;
              }
            }
          const std::size_t q = at(small, c, r);
          ASSERT_EQ(small.voxel[q], want) << c << "," << r;
          if (want >= 0) {
            EXPECT_EQ(small.shade[q], full.shade[static_cast<std::size_t>(want_pixel)]);
            EXPECT_EQ(small.normal[q], full.normal[static_cast<std::size_t>(want_pixel)]);
          } else {
            EXPECT_EQ(small.shade[q], 0.0f);
          }
        }
    }
  }
}

TEST(PreviewShrink, ThePngSaysHowMuchAPixelSpans) {
  BitVolume vol(unit_grid(40, 30, 20, 0.5));
  fill_box(vol, {3, 4, 2}, {36, 25, 17});
  const View top = view_of(kViews[0]);
  const json full = decode_png(preview_png(vol, top, nullptr, {}, 0, 0));
  const json fits = decode_png(preview_png(vol, top, nullptr, {}, 0, 40));
  EXPECT_EQ(full, fits);  // already fits: the same image
  EXPECT_FALSE(full["text"].contains("voxd:shrunk"));
  const json small = decode_png(preview_png(vol, top, nullptr, {}, 0, 16));
  EXPECT_EQ(small["width"], 14);  // 40 / 3, rounded up
  EXPECT_EQ(small["height"], 10);
  EXPECT_EQ(small["text"]["voxd:voxel_size"], "1.5 model units per pixel");
  EXPECT_EQ(small["text"]["voxd:shrunk"], "each pixel a block of 3 x 3 voxels, showing its nearest visible voxel");
  // The pixels are the shrunk image's, coloured as a full-size preview is.
  const PreviewImage shown = shrink_preview(render_preview(vol, top), vol.grid(), top, 3);
  for (std::int64_t r = 0; r < shown.height; ++r)
    for (std::int64_t c = 0; c < shown.width; ++c) {
      const std::size_t p = at(shown, c, r);
      const Rgb want = shown.voxel[p] < 0 ? Rgb{255, 255, 255} : shaded(kPreviewPartColour, shown.shade[p]);
      EXPECT_EQ(png_pixel(small, c, r), want) << c << "," << r;
    }
  // A thickness legend keeps its size: the same strip under a smaller map.
  DenseVolume<float> map(vol.grid(), 0.0f);
  for (std::int64_t k = 0; k < 20; ++k)
    for (std::int64_t j = 0; j < 30; ++j)
      for (std::int64_t i = 0; i < 40; ++i) map.at(i, j, k) = vol.get(i, j, k) ? 4.0f + static_cast<float>(i % 5) : 0.0f;
  const json coloured_full = decode_png(preview_png(vol, top, &map, {}, 0, 0));
  const json coloured_small = decode_png(preview_png(vol, top, &map, {}, 0, 20));
  EXPECT_EQ(coloured_full["width"], 40);
  EXPECT_EQ(coloured_full["height"], 30 + kLegendHeight);
  EXPECT_EQ(coloured_small["width"], 20);
  EXPECT_EQ(coloured_small["height"], 15 + kLegendHeight);
  EXPECT_EQ(coloured_small["text"]["voxd:legend"], coloured_full["text"]["voxd:legend"]);
}

TEST(PreviewPng, ThicknessColoursUseTheWholeMapRange) {
  // Two plates seen from +z: 4 voxels thick at small x, 8 at large x. One
  // voxel under the thick plate (hidden from +z) says 16: the ramp must span
  // the whole map, 4..16, not just the visible 4..8.
  const Grid g = unit_grid(40, 20, 12, 0.5);
  BitVolume vol(g);
  fill_box(vol, {2, 2, 2}, {17, 17, 5});
  fill_box(vol, {22, 2, 2}, {37, 17, 9});
  DenseVolume<float> thickness(g, 0.0f);
  for (std::int64_t k = 0; k < g.dims.z; ++k)
    for (std::int64_t j = 0; j < g.dims.y; ++j)
      for (std::int64_t i = 0; i < g.dims.x; ++i)
        if (vol.get(i, j, k)) thickness.at(i, j, k) = i < 20 ? 4.0f : 8.0f;
  thickness.at(30, 10, 2) = 16.0f;

  const PreviewImage img = render_preview(vol, View{2, true});
  const json png = decode_png(preview_png(vol, View{2, true}, &thickness, {{"voxd:source", "plates"}}));
  ASSERT_EQ(png["width"], 40);
  ASSERT_EQ(png["height"], 20 + kLegendHeight);
  const auto& text = png["text"];
  EXPECT_EQ(text["voxd:view"], "+z");
  EXPECT_EQ(text["voxd:min"], "2 model units");  // 4 voxels of 0.5
  EXPECT_EQ(text["voxd:max"], "8 model units");  // 16 voxels, though no pixel shows it
  EXPECT_EQ(text["voxd:scale"], "1 pixel value = 0.0625 model units");
  EXPECT_EQ(text["voxd:source"], "plates");
  const auto& ramp = thickness_ramp();
  const int thin = ramp_index(32, 32, 128), thick = ramp_index(64, 32, 128);
  ASSERT_EQ(thin, 0);
  ASSERT_EQ(thick, 85);
  int thin_pixels = 0, thick_pixels = 0;
  for (std::int64_t r = 0; r < img.height; ++r) {
    for (std::int64_t c = 0; c < img.width; ++c) {
      const std::size_t p = at(img, c, r);
      if (img.voxel[p] < 0) {
        EXPECT_EQ(png_pixel(png, c, r), (Rgb{255, 255, 255})) << c << "," << r;
        continue;
      }
      const bool is_thick = voxel_coords(vol, img.voxel[p]).x >= 20;
      (is_thick ? thick_pixels : thin_pixels)++;
      EXPECT_EQ(png_pixel(png, c, r), shaded(ramp[static_cast<std::size_t>(is_thick ? thick : thin)], img.shade[p]))
          << c << "," << r;
    }
  }
  EXPECT_EQ(thin_pixels, 16 * 16);
  EXPECT_EQ(thick_pixels, 16 * 16);
  // The legend is not shaded: its bar runs from ramp[0] to ramp[255] exactly.
  const int bar_row = 20 + kLegendMargin;
  EXPECT_EQ(png_pixel(png, kLegendMargin, bar_row), ramp[0]);
  EXPECT_EQ(png_pixel(png, 40 - kLegendMargin - 1, bar_row), ramp[255]);
  EXPECT_EQ(png_pixel(png, 0, 20), kLegendBackground);

  const DenseVolume<float> wrong(unit_grid(40, 20, 11));
  EXPECT_EQ(code_of([&] { preview_png(vol, View{2, true}, &wrong); }), ErrorCode::invalid_argument);
}

TEST(PreviewPng, ThicknessRangeIsTheWholeMapsOnAnyThreadCount) {
  // A map of 2.6M voxels is read in several chunks on several threads. Its
  // extremes sit in different chunks, at positions not on a block of eight;
  // NaN, negative and -0.0 values are not thicknesses. The legend's ends must
  // be the eighths of the extremes found here voxel by voxel, and the bytes
  // the same on 1 and 3 threads.
  const Grid g = unit_grid(160, 128, 128, 0.5);
  BitVolume vol(g);
  fill_box(vol, {4, 4, 4}, {155, 123, 123});
  DenseVolume<float> thickness(g, 0.0f);
  std::mt19937 rng(39);
  std::uniform_real_distribution<float> wall(2.0f, 30.0f);
  for (std::int64_t k = 0; k < g.dims.z; ++k)
    for (std::int64_t j = 0; j < g.dims.y; ++j)
      for (std::int64_t i = 0; i < g.dims.x; ++i)
        if (vol.get(i, j, k)) thickness.at(i, j, k) = wall(rng);
  thickness.at(7, 9, 5) = 37.0f;       // the largest, in the first chunk
  thickness.at(151, 117, 121) = 1.5f;  // the smallest, in the last
  thickness.at(33, 40, 50) = std::numeric_limits<float>::quiet_NaN();
  thickness.at(34, 40, 50) = -50.0f;
  thickness.at(35, 40, 50) = -0.0f;
  thickness.at(1, 1, 1) = 0.25f;  // outside the part, still the map's smallest
  float lo = std::numeric_limits<float>::infinity(), hi = 0.0f;
  for (const float t : thickness.values())
    if (t > 0.0f) lo = std::min(lo, t), hi = std::max(hi, t);
  ASSERT_EQ(lo, 0.25f);
  ASSERT_EQ(hi, 37.0f);

  const std::vector<std::uint8_t> one = preview_png(vol, View{2, true}, &thickness, {}, 1);
  EXPECT_EQ(preview_png(vol, View{2, true}, &thickness, {}, 3), one);
  const json png = decode_png(one);
  EXPECT_EQ(png["text"]["voxd:min"], "0.125 model units");  // 0.25 voxels = 2 eighths of 0.5
  EXPECT_EQ(png["text"]["voxd:max"], "18.5 model units");   // 37 voxels = 296 eighths

  const std::vector<std::uint8_t> section = section_png(vol, 2, 60, &thickness, {}, 1);
  EXPECT_EQ(section_png(vol, 2, 60, &thickness, {}, 3), section);
  const json decoded = decode_png(section);
  EXPECT_EQ(decoded["text"]["voxd:min"], "0.125 model units");
  EXPECT_EQ(decoded["text"]["voxd:max"], "18.5 model units");
}

}  // namespace
}  // namespace voxd
