#pragma once
// The analysis images as PNG bytes, shared by the HTTP routes and
// `voxd analyze` so both produce the same files.
#include <cstdint>
#include <string>
#include <vector>

#include "voxd/bit_volume.h"
#include "voxd/encode/colour_map.h"
#include "voxd/dense_volume.h"
#include "voxd/encode/png_image.h"
#include "voxd/analysis/preview.h"
#include "voxd/analysis/radiography.h"
#include "voxd/analysis/section.h"
#include "voxd/enum_names.h"
#include "voxd/voxelize/slice_functions.h"

namespace voxd {

enum class RadiographyMeasure { min, max, total };
inline constexpr EnumNames<RadiographyMeasure, 3> kRadiographyMeasureNames{{
    {RadiographyMeasure::min, "min"}, {RadiographyMeasure::max, "max"}, {RadiographyMeasure::total, "total"}}};
inline const char* to_string(RadiographyMeasure m) noexcept { return name_of(kRadiographyMeasureNames, m); }
const UnclearedVector<std::uint32_t>& values_of(const ThicknessImage& image, RadiographyMeasure m);

// 16-bit grey (pixel = thickness in voxels, exact) or, with `colour`, false
// colour with a legend. `scale` states what one pixel value is worth.
std::vector<std::uint8_t> radiography_png(const ThicknessImage& image, int axis, RadiographyMeasure measure, bool colour,
                                          const PngScale& scale, std::vector<PngText> text = {});

// 8-bit section through voxel layer `index` along `axis`, with its plane and
// pixel size in tEXt.
std::vector<std::uint8_t> section_png(const BitVolume& volume, int axis, std::int64_t index, std::vector<PngText> text = {});
// The same from the section already taken (cross_section or a
// SectionGatherer over slabs) of a volume on `grid`.
std::vector<std::uint8_t> section_png(const GreyImage8& section, const Grid& grid, int axis, std::int64_t index,
                                      std::vector<PngText> text = {});
// The same section coloured by local thickness (map in voxels on the same
// grid): filled pixels in the ramp colour of round(t * 8) over the whole
// map's range, empty ones white, legend strip below with labels in model
// units (as preview_png). A null map gives the grey section. The map's range
// is found on up to `threads` threads (0: every core); the bytes do not
// depend on the count.
std::vector<std::uint8_t> section_png(const BitVolume& volume, int axis, std::int64_t index,
                                      const DenseVolume<float>* thickness, std::vector<PngText> text = {},
                                      int threads = 0);

// Shaded preview (voxd/analysis/preview.h) as 8-bit RGB. Without `thickness`: the part
// in kPreviewPartColour times the shade, background white. With `thickness`
// (local thickness map in voxels on the same grid, 0 = empty; see
// voxd/analysis/local_thickness.h) each visible voxel takes the thickness ramp colour
// of round(t * 8) (voxd/encode/colour_map.h; range = smallest and largest non-zero
// value of the whole map, so hidden voxels count; legend strip under the
// image, labels in model units: PngScale{voxel_size / 8, "model units"})
// times the shade; legend rows stay unshaded, and a visible voxel the map
// gives no thickness keeps kPreviewPartColour. tEXt: voxd:view, voxd:right,
// voxd:up, voxd:voxel_size, voxd:lighting, the colour map's chunks when
// coloured, then `text`. Throws Error(invalid_argument) when the map's dims
// differ from the volume's or the volume has a zero dimension.
// `max_side` > 0: an image larger than max_side x max_side is shrunk by the
// smallest integer factor that fits (shrink_preview: each pixel its block's
// nearest visible voxel; voxd:voxel_size then counts the block, and
// voxd:shrunk says so). The legend keeps its size. 0: one pixel a voxel.
inline constexpr Rgb kPreviewPartColour{176, 190, 210};  // steel blue-grey
std::vector<std::uint8_t> preview_png(const BitVolume& volume, View view, const DenseVolume<float>* thickness,
                                      std::vector<PngText> text = {}, int threads = 0, int max_side = 0);
// The same from a rendered preview (a PreviewRenderer's over slabs) of a
// volume on `grid`, without a thickness map: the bytes preview_png gives.
std::vector<std::uint8_t> preview_png(const PreviewImage& preview, const Grid& grid, View view,
                                      std::vector<PngText> text = {}, int max_side = 0);
// The same view with each visible voxel in its own colour (a slice job's
// colours; alpha ignored), shaded alike. Throws as preview_png, and when the
// colours' dims differ from the volume's.
std::vector<std::uint8_t> colour_preview_png(const BitVolume& volume, const DenseVolume<Rgba8>& colours, View view,
                                             std::vector<PngText> text = {}, int threads = 0, int max_side = 0);
// The same view of a solid coloured by a slice function without its volume:
// each visible voxel's colour from `colours` (voxd/voxelize/slice_functions.h).
// The bytes colour_preview_png gives for voxelize_slice's volume of the same
// solid, options and frame. Throws as preview_png, and when the solid's grid
// is not the colours'.
std::vector<std::uint8_t> slice_preview_png(const BitVolume& volume, const SliceColours& colours, View view,
                                            std::vector<PngText> text = {}, int threads = 0, int max_side = 0);
// The same from the solid's preview already rendered (render_preview of
// the volume on `grid` from `view`): an editor's next colours cost only the
// visible voxels' colours. `compression` as slice_section_png's.
std::vector<std::uint8_t> slice_preview_png(const PreviewImage& preview, const Grid& grid, const SliceColours& colours,
                                            View view, std::vector<PngText> text = {}, int threads = 0, int max_side = 0,
                                            PngCompression compression = PngCompression::balanced);

}  // namespace voxd
