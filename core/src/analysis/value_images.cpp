#include "voxd/analysis/value_images.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <string>

#include "voxd/byte_sink.h"
#include "voxd/encode/colour_map.h"
#include "voxd/error.h"
#include "voxd/encode/number_text.h"
#include "voxd/analysis/radiography.h"
#include "voxd/parallel.h"

namespace voxd {
namespace {

const char* axis_name(int axis) { return axis == 0 ? "x" : axis == 1 ? "y" : "z"; }

// The section's size; throws for a bad axis, index or size.
ImageSize section_size(const Grid& grid, int axis, std::int64_t index) {
  const ImageSize size = projected_size(grid, axis);  // checks the axis and the size
  const glm::i64vec3 d = grid.dims;
  if (index < 0 || index >= d[axis]) {
    throw Error(ErrorCode::invalid_argument, std::string("section index along ") + axis_name(axis) + " is " +
                                                 std::to_string(index) + ", outside 0.." + std::to_string(d[axis] - 1));
  }
  return size;
}

template <class T>
ValueSection<T> extract(const DenseVolume<T>& volume, int axis, std::int64_t index) {
  const ImageSize size = section_size(volume.grid(), axis, index);
  const glm::i64vec3 d = volume.grid().dims;
  if (volume.values().size() != volume.grid().voxel_count()) {
    throw Error(ErrorCode::invalid_argument, "section: the volume holds " + std::to_string(volume.values().size()) +
                                                 " values for " + std::to_string(volume.grid().voxel_count()) + " voxels");
  }
  ValueSection<T> out;
  out.width = size.width;
  out.height = size.height;
  out.values.resize(static_cast<std::size_t>(size.width) * static_cast<std::size_t>(size.height));
  T* dst = out.values.data();
  if (axis == 2) {
    const T* slab = volume.slab(index);
    std::copy(slab, slab + volume.slab_size(), dst);
  } else if (axis == 1) {  // row k = x-row (index, k)
    for (std::int64_t k = 0; k < d.z; ++k) {
      const T* row = &volume.at(0, index, k);
      std::copy(row, row + d.x, dst + k * d.x);
    }
  } else {  // column j, row k
    for (std::int64_t k = 0; k < d.z; ++k)
      for (std::int64_t j = 0; j < d.y; ++j) dst[k * d.y + j] = volume.at(index, j, k);
  }
  return out;
}

std::vector<PngText> plane_text(const Grid& g, int axis, std::int64_t index, std::vector<PngText> chunks,
                                const std::vector<PngText>& text) {
  const double plane = g.origin[axis] + (static_cast<double>(index) + 0.5) * g.voxel_size;
  chunks.insert(chunks.begin(), {{"voxd:axis", axis_name(axis)},
                                 {"voxd:index", std::to_string(index)},
                                 {"voxd:plane", number_text(plane) + " model units (voxel centres)"},
                                 {"voxd:voxel_size", number_text(g.voxel_size) + " model units per pixel"}});
  chunks.insert(chunks.end(), text.begin(), text.end());
  return chunks;
}

const PngText kCoverageText{"voxd:coverage", "pixel = round(255 x the fraction of the voxel inside the part)"};

std::vector<std::uint8_t> grey_png(const ValueSection<std::uint8_t>& s, const std::vector<PngText>& text) {
  VectorSink out;
  write_png_grey8(s.width, s.height, s.values, text, out);
  return std::move(out.data);
}

void check_field(const SdfRenderInput& input) {
  if (!input.sdf) throw Error(ErrorCode::invalid_argument, "sdf section: no signed distance field given");
  if (!(input.units_per_voxel > 0.0) || !std::isfinite(input.units_per_voxel)) {
    throw Error(ErrorCode::invalid_argument,
                "sdf section: units_per_voxel must be a positive finite number, got " + number_text(input.units_per_voxel));
  }
}

}  // namespace

ValueSection<float> value_section(const DenseVolume<float>& volume, int axis, std::int64_t index) {
  return extract(volume, axis, index);
}
ValueSection<std::uint8_t> value_section(const DenseVolume<std::uint8_t>& volume, int axis, std::int64_t index) {
  return extract(volume, axis, index);
}

std::vector<std::uint8_t> coverage_section_png(const DenseVolume<std::uint8_t>& coverage, int axis, std::int64_t index,
                                               std::vector<PngText> text) {
  const ValueSection<std::uint8_t> s = extract(coverage, axis, index);
  return grey_png(s, plane_text(coverage.grid(), axis, index, {kCoverageText}, text));
}

namespace {

ValueSection<std::uint8_t> as_bytes(const ValueSection<float>& f) {
  ValueSection<std::uint8_t> s{f.width, f.height, std::vector<std::uint8_t>(f.values.size())};
  for (std::size_t p = 0; p < f.values.size(); ++p) {  // as coverage_bytes()
    s.values[p] = static_cast<std::uint8_t>(std::lround(std::clamp(f.values[p], 0.0f, 1.0f) * 255.0f));
  }
  return s;
}

}  // namespace

std::vector<std::uint8_t> coverage_section_png(const DenseVolume<float>& coverage, int axis, std::int64_t index,
                                               std::vector<PngText> text) {
  // The section first: it checks the axis and the index the plane's text uses.
  const ValueSection<std::uint8_t> s = as_bytes(extract(coverage, axis, index));
  return grey_png(s, plane_text(coverage.grid(), axis, index, {kCoverageText}, text));
}

CoverageSectionGatherer::CoverageSectionGatherer(const Grid& grid, int axis, std::int64_t index)
    : grid_(grid), axis_(axis), index_(index) {
  const ImageSize size = section_size(grid, axis, index);
  section_.width = size.width;
  section_.height = size.height;
  section_.values.assign(static_cast<std::size_t>(size.width) * static_cast<std::size_t>(size.height), 0);
}

void CoverageSectionGatherer::add(std::int64_t k0, const DenseVolume<std::uint8_t>& slab) {
  const std::int64_t n = slab.grid().dims.z;
  if (axis_ == 2) {
    if (index_ >= k0 && index_ < k0 + n) section_.values = extract(slab, 2, index_ - k0).values;
    return;
  }
  // Rows are z layers: the slab's rows go to rows k0.. of the section.
  const ValueSection<std::uint8_t> rows = extract(slab, axis_, index_);
  std::copy(rows.values.begin(), rows.values.end(), section_.values.begin() + k0 * section_.width);
}

void CoverageSectionGatherer::add(std::int64_t k0, const DenseVolume<float>& slab) {
  const std::int64_t n = slab.grid().dims.z;
  if (axis_ == 2) {
    if (index_ >= k0 && index_ < k0 + n) section_.values = as_bytes(extract(slab, 2, index_ - k0)).values;
    return;
  }
  const ValueSection<std::uint8_t> rows = as_bytes(extract(slab, axis_, index_));
  std::copy(rows.values.begin(), rows.values.end(), section_.values.begin() + k0 * section_.width);
}

std::vector<std::uint8_t> CoverageSectionGatherer::png(std::vector<PngText> text) const {
  return grey_png(section_, plane_text(grid_, axis_, index_, {kCoverageText}, text));
}

namespace {

// Colours over white (alpha blended, rounded), as one PNG.
std::vector<std::uint8_t> colour_png(const ValueSection<Rgba8>& s, const Grid& grid, int axis, std::int64_t index,
                                     const std::vector<PngText>& text,
                                     PngCompression compression = PngCompression::balanced) {
  RgbImage image{s.width, s.height, std::vector<std::uint8_t>(s.values.size() * 3)};
  for (std::size_t p = 0; p < s.values.size(); ++p) {
    const Rgba8 c = s.values[p];
    const std::uint8_t rgb[3] = {c.r, c.g, c.b};
    for (int ch = 0; ch < 3; ++ch)
      image.pixels[3 * p + static_cast<std::size_t>(ch)] =
          static_cast<std::uint8_t>((rgb[ch] * c.a + 255 * (255 - c.a) + 127) / 255);
  }
  VectorSink out;
  write_png_rgb8(image, plane_text(grid, axis, index, {{"voxd:colour", "the voxel's colour over white"}}, text), out,
                 compression);
  return std::move(out.data);
}

}  // namespace

std::vector<std::uint8_t> colour_section_png(const DenseVolume<Rgba8>& colours, int axis, std::int64_t index,
                                             std::vector<PngText> text) {
  return colour_png(extract(colours, axis, index), colours.grid(), axis, index, text);
}

std::vector<std::uint8_t> slice_section_png(const BitVolume& solid, const SliceColours& colours, int axis,
                                            std::int64_t index, std::vector<PngText> text, int threads,
                                            PngCompression compression) {
  const Grid& g = solid.grid();
  if (g.dims != colours.grid().dims)
    throw Error(ErrorCode::invalid_argument, "slice section: the solid's grid is not the slice colours' grid");
  const ImageSize size = section_size(g, axis, index);
  ValueSection<Rgba8> s;
  s.width = size.width;
  s.height = size.height;
  s.values.assign(static_cast<std::size_t>(size.width) * static_cast<std::size_t>(size.height), Rgba8{0, 0, 0, 0});
  // Image row r is layer r along the row axis (z, or y for a z section);
  // column c runs along x, or y for an x section.
  parallel_for(0, size.height, 8, threads, [&](std::int64_t r0, std::int64_t r1) {
    for (std::int64_t r = r0; r < r1; ++r) {
      Rgba8* out = &s.values[static_cast<std::size_t>(r * size.width)];
      if (axis == 0) {  // column j of voxels (index, j, r)
        for (std::int64_t j = 0; j < size.width; ++j)
          if (solid.get(index, j, r)) out[j] = colours.at(index, j, r);
        continue;
      }
      const std::int64_t j = axis == 2 ? r : index, k = axis == 2 ? index : r;
      const std::uint64_t* row = solid.row(j, k);
      const glm::dvec3 start = colours.row_start(j, k);
      for (std::int64_t word = 0; word < solid.row_words(); ++word)
        for (std::uint64_t bits = row[word]; bits != 0; bits &= bits - 1) {
          const std::int64_t i = word * 64 + std::countr_zero(bits);
          out[i] = colours.along_row(start, i);
        }
    }
  });
  return colour_png(s, g, axis, index, text, compression);
}

double sdf_section_range(const SdfRenderInput& input) {
  if (!input.sdf) throw Error(ErrorCode::invalid_argument, "sdf section: no signed distance field given");
  float range = 0.0f;
  for (const float v : input.sdf->values()) {
    if (std::isfinite(v)) range = std::max(range, std::abs(v));
  }
  return range;
}

std::vector<std::uint8_t> sdf_section_png(const SdfRenderInput& input, int axis, std::int64_t index, bool colour,
                                          std::vector<PngText> text) {
  check_field(input);
  const ValueSection<float> s = extract(*input.sdf, axis, index);
  const double found = sdf_section_range(input);
  const double range = found > 0.0 ? found : 1.0;
  const std::string& unit = input.unit;
  std::vector<PngText> chunks = {{"voxd:unit", unit},
                                 {"voxd:range", number_text(found) + " " + unit},
                                 {"voxd:sign", input.inside_negative ? "inside negative" : "inside positive"}};
  VectorSink out;
  if (!colour) {
    std::vector<std::uint8_t> grey(s.values.size());
    for (std::size_t p = 0; p < s.values.size(); ++p) {
      const double v = static_cast<double>(s.values[p]);
      const double g = std::isnan(v) ? 128.0 : std::clamp(127.5 + 127.5 * v / range, 0.0, 255.0);
      grey[p] = static_cast<std::uint8_t>(std::lround(g));
    }
    chunks.push_back({"voxd:min", number_text(-range) + " " + unit});
    chunks.push_back({"voxd:max", number_text(range) + " " + unit});
    chunks.push_back({"voxd:grey", "pixel = round(127.5 + 127.5 x value / " + number_text(range) +
                                       "), clamped to 0..255: -range is 0, 0 is 128, +range is 255"});
    write_png_grey8(s.width, s.height, grey, plane_text(input.sdf->grid(), axis, index, std::move(chunks), text), out);
    return std::move(out.data);
  }
  DivergingMapOptions options;
  options.range = range;
  options.unit = unit;
  options.positive_blue = !input.inside_negative;
  DivergingMap map = render_diverging_map(s.width, s.height, s.values, options);
  for (PngText& t : map.text) {
    if (t.key != "voxd:unit") chunks.push_back(std::move(t));
  }
  write_png_rgb8(map.image, plane_text(input.sdf->grid(), axis, index, std::move(chunks), text), out);
  return std::move(out.data);
}

}  // namespace voxd
