#include "voxd/analysis_images.h"

#include <charconv>

#include "voxd/byte_sink.h"
#include "voxd/colour_map.h"
#include "voxd/section.h"

namespace voxd {
namespace {

std::string number(double x) {
  char buf[32];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, x);
  (void)ec;
  return std::string(buf, end);
}

}  // namespace

const char* to_string(RadiographyMeasure m) {
  switch (m) {
    case RadiographyMeasure::min: return "min";
    case RadiographyMeasure::max: return "max";
    case RadiographyMeasure::total: return "total";
  }
  return "?";
}

const std::vector<std::uint32_t>& values_of(const ThicknessImage& image, RadiographyMeasure m) {
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

std::vector<std::uint8_t> section_png(const BitVolume& volume, int axis, std::int64_t index, std::vector<PngText> text) {
  const Grid& g = volume.grid();
  const GreyImage8 image = cross_section(volume, axis, index);
  const double plane = g.origin[axis] + (static_cast<double>(index) + 0.5) * g.voxel_size;
  text.insert(text.begin(), {{"voxd:axis", std::string(1, "xyz"[axis])},
                             {"voxd:index", std::to_string(index)},
                             {"voxd:plane", number(plane) + " model units (voxel centres)"},
                             {"voxd:voxel_size", number(g.voxel_size) + " model units per pixel"}});
  VectorSink out;
  write_png_grey8(image.width, image.height, image.pixels, text, out);
  return std::move(out.data);
}

}  // namespace voxd
