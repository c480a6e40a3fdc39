#pragma once
// The analysis images as PNG bytes, shared by the HTTP routes and
// `voxd analyze` so both produce the same files.
#include <cstdint>
#include <string>
#include <vector>

#include "voxd/bit_volume.h"
#include "voxd/png_image.h"
#include "voxd/radiography.h"

namespace voxd {

enum class RadiographyMeasure { min, max, total };
const char* to_string(RadiographyMeasure m);
const std::vector<std::uint32_t>& values_of(const ThicknessImage& image, RadiographyMeasure m);

// 16-bit grey (pixel = thickness in voxels, exact) or, with `colour`, false
// colour with a legend. `scale` states what one pixel value is worth.
std::vector<std::uint8_t> radiography_png(const ThicknessImage& image, int axis, RadiographyMeasure measure, bool colour,
                                          const PngScale& scale, std::vector<PngText> text = {});

// 8-bit section through voxel layer `index` along `axis`, with its plane and
// pixel size in tEXt.
std::vector<std::uint8_t> section_png(const BitVolume& volume, int axis, std::int64_t index, std::vector<PngText> text = {});

}  // namespace voxd
