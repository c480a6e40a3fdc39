#include "voxd/analysis/analysis_images.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <utility>

#include "voxd/byte_sink.h"
#include "voxd/encode/colour_map.h"
#include "voxd/encode/number_text.h"
#include "voxd/error.h"
#include "voxd/analysis/section.h"
#include "voxd/parallel.h"
#include "analysis/zero_skip.h"

namespace voxd {
const UnclearedVector<std::uint32_t>& values_of(const ThicknessImage& image, RadiographyMeasure m) {
  return m == RadiographyMeasure::min ? image.min : m == RadiographyMeasure::max ? image.max : image.total;
}

std::vector<std::uint8_t> radiography_png(const ThicknessImage& image, int axis, RadiographyMeasure measure, bool colour,
                                          const PngScale& scale, std::vector<PngText> text) {
  text.push_back({"voxd:measure", std::string(to_string(measure)) + " thickness along " + std::string(1, "xyz"[axis])});
  VectorSink out;
  const auto& values = values_of(image, measure);
  if (!colour) {
    write_png_grey16(image.width, image.height, values, scale, text, out);
  } else {
    ColourMapOptions options;
    options.scale = scale;
    ColourMap map = render_thickness_map(image.width, image.height, values, options);
    map.text.insert(map.text.end(), text.begin(), text.end());
    write_png_rgb8(map.image, map.text, out);
  }
  return std::move(out.data);
}

namespace {

std::string signed_axis(int axis, bool positive) { return std::string(positive ? "+" : "-") + "xyz"[axis]; }

// Thickness map values (voxels, float) as the colour map's integers: eighths
// of a voxel, fine enough that the ramp never shows the rounding.
std::uint32_t eighths(float t) {
  if (!(t > 0.0f)) return 0;
  return std::max<std::uint32_t>(1, static_cast<std::uint32_t>(std::lround(static_cast<double>(t) * 8.0)));
}

void shade_into(std::uint8_t* px, Rgb c, float shade) {
  px[0] = static_cast<std::uint8_t>(std::lround(c.r * shade));
  px[1] = static_cast<std::uint8_t>(std::lround(c.g * shade));
  px[2] = static_cast<std::uint8_t>(std::lround(c.b * shade));
}

// The smallest and largest value > 0 of a map (a thickness map is 0 outside
// the part, most of a padded grid), on up to `threads` threads. Minimum and
// maximum do not depend on the order they are taken in, so the range is the
// same for any thread count. NaN is not > 0 and is left out.
struct PositiveRange {
  float min = std::numeric_limits<float>::infinity();
  float max = 0.0f;  // stays 0 when nothing is > 0
};

PositiveRange positive_range(const DenseVolume<float>& map, int threads) {
  const float* v = map.values().data();
  const auto n = static_cast<std::int64_t>(map.values().size());
  constexpr std::int64_t kGrain = std::int64_t{1} << 20;  // 4 MiB of floats a chunk
  std::vector<PositiveRange> chunks(static_cast<std::size_t>((n + kGrain - 1) / kGrain));
  parallel_for(0, n, kGrain, threads, [&](std::int64_t begin, std::int64_t end) {
    PositiveRange r;
    for (std::int64_t i = detail::skip_zero_blocks(v, begin, end); i < end; i = detail::skip_zero_blocks(v, i, end)) {
      const std::int64_t stop = std::min(end, i + 8);
      for (; i < stop; ++i) {
        const float t = v[i];
        if (!(t > 0.0f)) continue;
        r.min = std::min(r.min, t);
        r.max = std::max(r.max, t);
      }
    }
    chunks[static_cast<std::size_t>(begin / kGrain)] = r;
  });
  PositiveRange all;
  for (const PositiveRange& r : chunks) {
    all.min = std::min(all.min, r.min);
    all.max = std::max(all.max, r.max);
  }
  return all;
}

// The colour map options for a local thickness map: labels in model units,
// ramp over the whole map's non-zero range. eighths() never decreases as t
// grows, so the range of the voxels' eighths is the eighths of the map's
// positive range.
ColourMapOptions thickness_colours(const DenseVolume<float>& thickness, double voxel_size, int threads) {
  ColourMapOptions options;
  options.scale = PngScale{voxel_size / 8.0, "model units"};
  const PositiveRange range = positive_range(thickness, threads);
  if (range.max > 0.0f) {
    options.range_min = eighths(range.min);
    options.range_max = eighths(range.max);
  }
  return options;
}

}  // namespace

namespace {

// A section's plane and pixel size, for its tEXt chunks.
std::vector<PngText> section_text(const Grid& g, int axis, std::int64_t index) {
  const double plane = g.origin[axis] + (static_cast<double>(index) + 0.5) * g.voxel_size;
  return {{"voxd:axis", std::string(1, "xyz"[axis])},
          {"voxd:index", std::to_string(index)},
          {"voxd:plane", number_text(plane) + " model units (voxel centres)"},
          {"voxd:voxel_size", number_text(g.voxel_size) + " model units per pixel"}};
}

}  // namespace

std::vector<std::uint8_t> section_png(const GreyImage8& section, const Grid& grid, int axis, std::int64_t index,
                                      std::vector<PngText> text) {
  const std::vector<PngText> plane = section_text(grid, axis, index);
  text.insert(text.begin(), plane.begin(), plane.end());
  VectorSink out;
  write_png_grey8(section.width, section.height, section.pixels, text, out);
  return std::move(out.data);
}

std::vector<std::uint8_t> section_png(const BitVolume& volume, int axis, std::int64_t index, std::vector<PngText> text) {
  return section_png(volume, axis, index, nullptr, std::move(text));
}

std::vector<std::uint8_t> section_png(const BitVolume& volume, int axis, std::int64_t index,
                                      const DenseVolume<float>* thickness, std::vector<PngText> text, int threads) {
  const Grid& g = volume.grid();
  if (thickness && thickness->grid().dims != g.dims) {
    throw Error(ErrorCode::invalid_argument, "section: the thickness map's grid does not match the volume's");
  }
  const GreyImage8 image = cross_section(volume, axis, index);
  if (!thickness) return section_png(image, g, axis, index, std::move(text));
  const std::vector<PngText> plane = section_text(g, axis, index);
  text.insert(text.begin(), plane.begin(), plane.end());
  VectorSink out;
  // Each filled pixel in the ramp colour of its voxel's thickness, over the
  // whole map's range so every section of a part shares one legend.
  ColourMapOptions options = thickness_colours(*thickness, g.voxel_size, threads);
  const int c_axis = axis == 0 ? 1 : 0, r_axis = axis == 2 ? 1 : 2;
  std::vector<std::uint32_t> values(image.pixels.size(), 0);
  for (int r = 0; r < image.height; ++r)
    for (int c = 0; c < image.width; ++c) {
      if (image.pixels[static_cast<std::size_t>(r) * image.width + c] == 0) continue;
      std::int64_t ijk[3];
      ijk[axis] = index;
      ijk[c_axis] = c;
      ijk[r_axis] = r;
      values[static_cast<std::size_t>(r) * image.width + c] = eighths(thickness->at(ijk[0], ijk[1], ijk[2]));
    }
  ColourMap map = render_thickness_map(image.width, image.height, values, options, threads);
  map.text.insert(map.text.begin(), text.begin(), text.end());
  write_png_rgb8(map.image, map.text, out);
  return std::move(out.data);
}

namespace {

// Before the rendering's work: the maps must be on the volume's grid.
void check_preview_maps(const Grid& g, const DenseVolume<float>* thickness, const DenseVolume<Rgba8>* colours) {
  if (colours && colours->grid().dims != g.dims)
    throw Error(ErrorCode::invalid_argument, "preview: the colour volume's grid does not match the volume's");
  if (thickness && thickness->grid().dims != g.dims)
    throw Error(ErrorCode::invalid_argument, "preview: the thickness map's grid does not match the volume's");
}

// The preview in the part's grey-blue, coloured by thickness, or in each
// visible voxel's own colour.
// A visible voxel's own colour, by its index in the volume.
using VoxelColour = std::function<Rgba8(std::int64_t)>;

std::vector<std::uint8_t> render_preview_png(const PreviewImage& rendered, const Grid& g, View view,
                                             const DenseVolume<float>* thickness, const VoxelColour& colours,
                                             std::vector<PngText> text, int max_side, int threads,
                                             PngCompression compression = PngCompression::balanced) {
  const int factor = shrink_factor(rendered.width, rendered.height, max_side);
  const PreviewImage shrunk = factor > 1 ? shrink_preview(rendered, g, view, factor) : PreviewImage{};
  const PreviewImage& preview = factor > 1 ? shrunk : rendered;
  const int block = preview.block;  // rendered shrunk already (render_preview's max_side), or here
  const ViewBasis basis = view_basis(view);
  std::vector<PngText> chunks = {
      {"voxd:view", to_string(view)},
      {"voxd:right", signed_axis(basis.right_axis, basis.right_positive)},
      {"voxd:up", signed_axis(basis.up_axis, basis.up_positive)},
      {"voxd:voxel_size", number_text(g.voxel_size * block) + " model units per pixel"},
      {"voxd:lighting",
       "Orthographic view of the first filled voxel on each ray, normals from its 26 neighbours (Patil & Ravi) "
       "smoothed over 3x3 pixels, lit from the viewer's upper left: shade = 0.2 + 0.8 max(0, n.L), up to 20% darker "
       "with depth."}};
  if (block > 1)
    chunks.push_back({"voxd:shrunk", "each pixel a block of " + std::to_string(block) + " x " + std::to_string(block) +
                                         " voxels, showing its nearest visible voxel"});
  const std::size_t pixels = preview.voxel.size();
  RgbImage image;
  if (!thickness) {
    image.width = preview.width;
    image.height = preview.height;
    image.pixels.assign(pixels * 3, 255);
    // A pixel's colour is its own voxel's: the rows are shaded in parallel.
    parallel_for(0, preview.height, 16, threads, [&](std::int64_t r0, std::int64_t r1) {
      for (std::size_t p = static_cast<std::size_t>(r0 * preview.width); p < static_cast<std::size_t>(r1 * preview.width);
           ++p) {
        if (preview.voxel[p] < 0) continue;
        Rgb c = kPreviewPartColour;
        if (colours) {
          const Rgba8 v = colours(preview.voxel[p]);
          c = {v.r, v.g, v.b};
        }
        shade_into(&image.pixels[3 * p], c, preview.shade[p]);
      }
    });
    if (colours) chunks.push_back({"voxd:colour", "each visible voxel's own colour (its alpha ignored), shaded"});
  } else {
    // Range over the whole map, not the visible voxels: the legend then
    // matches the thickness report and the other views of the same part.
    const ColourMapOptions options = thickness_colours(*thickness, g.voxel_size, threads);
    // Every pixel is its own voxel's: the rows go to any thread.
    const auto rows_pixels = [&](std::int64_t r0, std::int64_t r1) {
      return std::pair{static_cast<std::size_t>(r0 * preview.width), static_cast<std::size_t>(r1 * preview.width)};
    };
    std::vector<std::uint32_t> values(pixels, 0);
    parallel_for(0, preview.height, 16, threads, [&](std::int64_t r0, std::int64_t r1) {
      const auto [begin, end] = rows_pixels(r0, r1);
      for (std::size_t p = begin; p < end; ++p)
        if (preview.voxel[p] >= 0) values[p] = eighths(thickness->values()[static_cast<std::size_t>(preview.voxel[p])]);
    });
    ColourMap map = render_thickness_map(preview.width, preview.height, values, options, threads);
    image = std::move(map.image);
    parallel_for(0, preview.height, 16, threads, [&](std::int64_t r0, std::int64_t r1) {
      const auto [begin, end] = rows_pixels(r0, r1);
      for (std::size_t p = begin; p < end; ++p) {  // the map rows only: the legend keeps its true colours
        if (preview.voxel[p] < 0) continue;
        std::uint8_t* px = &image.pixels[3 * p];
        const Rgb c = values[p] == 0 ? kPreviewPartColour : Rgb{px[0], px[1], px[2]};
        shade_into(px, c, preview.shade[p]);
      }
    });
    chunks.insert(chunks.end(), map.text.begin(), map.text.end());
  }
  chunks.insert(chunks.end(), text.begin(), text.end());
  VectorSink out;
  write_png_rgb8(image, chunks, out, compression, threads);
  return std::move(out.data);
}

}  // namespace

std::vector<std::uint8_t> preview_png(const BitVolume& volume, View view, const DenseVolume<float>* thickness,
                                      std::vector<PngText> text, int threads, int max_side) {
  check_preview_maps(volume.grid(), thickness, nullptr);
  return render_preview_png(render_preview(volume, view, threads, max_side), volume.grid(), view, thickness, {},
                            std::move(text), max_side, threads);
}

std::vector<std::uint8_t> preview_png(const PreviewImage& preview, const Grid& grid, View view, std::vector<PngText> text,
                                      int max_side) {
  return render_preview_png(preview, grid, view, nullptr, {}, std::move(text), max_side, 0);
}

std::vector<std::uint8_t> colour_preview_png(const BitVolume& volume, const DenseVolume<Rgba8>& colours, View view,
                                             std::vector<PngText> text, int threads, int max_side) {
  check_preview_maps(volume.grid(), nullptr, &colours);
  const Rgba8* values = colours.values().data();
  return render_preview_png(render_preview(volume, view, threads, max_side), volume.grid(), view, nullptr,
                            [values](std::int64_t voxel) { return values[voxel]; }, std::move(text), max_side, threads);
}

std::vector<std::uint8_t> slice_preview_png(const BitVolume& volume, const SliceColours& colours, View view,
                                            std::vector<PngText> text, int threads, int max_side) {
  return slice_preview_png(render_preview(volume, view, threads, max_side), volume.grid(), colours, view, std::move(text),
                           threads, max_side);
}

std::vector<std::uint8_t> slice_preview_png(const PreviewImage& preview, const Grid& grid, const SliceColours& colours,
                                            View view, std::vector<PngText> text, int threads, int max_side,
                                            PngCompression compression) {
  if (grid.dims != colours.grid().dims)
    throw Error(ErrorCode::invalid_argument, "slice preview: the solid's grid is not the slice colours' grid");
  const std::int64_t nx = grid.dims.x, ny = grid.dims.y;
  return render_preview_png(preview, grid, view, nullptr,
                            [&colours, nx, ny](std::int64_t voxel) {
                              return colours.at(voxel % nx, voxel / nx % ny, voxel / (nx * ny));
                            },
                            std::move(text), max_side, threads, compression);
}

}  // namespace voxd
