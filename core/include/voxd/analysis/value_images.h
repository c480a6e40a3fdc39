#pragma once
// Sections of value volumes (coverage, signed distance) as PNG images: one
// voxel layer across an axis, with the same columns and rows as the binary
// section (voxd/analysis/section.h cross_section(): axis 0 -> (j, k), 1 -> (i, k),
// 2 -> (i, j); pixel (c, r) at r * width + c, row r = layer index r along the
// row axis), so a value section overlays the binary one pixel for pixel.
//
// Every PNG carries tEXt voxd:axis, voxd:index, voxd:plane (the layer's
// coordinate: its voxel centres, in model units) and voxd:voxel_size, then
// its own chunks, then `text`.
#include <cstdint>
#include <vector>

#include "voxd/bit_volume.h"
#include "voxd/dense_volume.h"
#include "voxd/encode/png_image.h"
#include "voxd/analysis/sdf_render.h"
#include "voxd/voxelize/slice_functions.h"

namespace voxd {

// The values of one layer (width/height as cross_section()). Throws
// Error(invalid_argument) for an axis outside 0..2 or an index outside
// [0, dims[axis]) ("section index along z is 40, outside 0..31"), and
// Error(limit_exceeded) when the image would not fit an int.
template <class T>
struct ValueSection {
  int width = 0;
  int height = 0;
  std::vector<T> values;
};
ValueSection<float> value_section(const DenseVolume<float>& volume, int axis, std::int64_t index);
ValueSection<std::uint8_t> value_section(const DenseVolume<std::uint8_t>& volume, int axis, std::int64_t index);

// Coverage section, 8-bit grey: pixel = the coverage byte (0 = empty, 255 =
// full), from Thon's bytes as they are or from coverage in [0, 1] as
// coverage_bytes() makes them (round(255 v), v clamped to [0, 1]). tEXt
// voxd:coverage says so. Throws as value_section().
std::vector<std::uint8_t> coverage_section_png(const DenseVolume<std::uint8_t>& coverage, int axis, std::int64_t index,
                                               std::vector<PngText> text = {});
std::vector<std::uint8_t> coverage_section_png(const DenseVolume<float>& coverage, int axis, std::int64_t index,
                                               std::vector<PngText> text = {});

// coverage_section_png() of a coverage that arrives slab by slab in z order
// (a streamed job's stored values): add() every slab, then png(); the bytes
// coverage_section_png() gives for the whole volume. Memory is the section.
// Throws as value_section() for a bad axis or index.
class CoverageSectionGatherer {
 public:
  CoverageSectionGatherer(const Grid& grid, int axis, std::int64_t index);
  // Layers [k0, k0 + slab.grid().dims.z) of the grid.
  void add(std::int64_t k0, const DenseVolume<std::uint8_t>& slab);
  void add(std::int64_t k0, const DenseVolume<float>& slab);
  std::vector<std::uint8_t> png(std::vector<PngText> text = {}) const;

 private:
  Grid grid_;
  int axis_;
  std::int64_t index_;
  ValueSection<std::uint8_t> section_;
};

// A slice job's colours in a section, 8-bit RGB: each voxel's colour over a
// white background (alpha blended: c * a / 255 + 255 * (1 - a / 255),
// rounded), so empty voxels are white. Same layout as the other sections.
std::vector<std::uint8_t> colour_section_png(const DenseVolume<Rgba8>& colours, int axis, std::int64_t index,
                                             std::vector<PngText> text = {});
// The same section of a solid coloured by a slice function without its
// volume: each filled voxel of layer `index` its colour from `colours`
// (voxd/voxelize/slice_functions.h), on up to `threads` threads (0: every
// core). The bytes colour_section_png gives for voxelize_slice's volume of
// the same solid, options and frame. Throws as colour_section_png, and when
// the solid's grid is not the colours'. `compression` fast: the same
// pixels, encoded for an editor's next picture rather than for keeping.
std::vector<std::uint8_t> slice_section_png(const BitVolume& solid, const SliceColours& colours, int axis,
                                            std::int64_t index, std::vector<PngText> text = {}, int threads = 0,
                                            PngCompression compression = PngCompression::balanced);

// The symmetric range of a field's sections: the largest |value| over the
// whole field (non-finite values skipped; with a clamped narrow band, the
// band), so every section of one field shares one scale; 0 for a field of
// zeros. Throws Error(invalid_argument) for a null field.
double sdf_section_range(const SdfRenderInput& input);

// Signed distance section. R = sdf_section_range(input) (1 where that is 0).
//  - colour: 8-bit RGB through the diverging ramp (voxd/encode/colour_map.h) on
//    [-R, R], inside always blue and outside red whatever the sign
//    convention, 0 exactly white; legend strip under the map (when at least
//    kLegendMinWidth pixels wide) labelled in input.unit with the values at
//    its ends (-R left for inside negative, +R left for inside positive).
//  - grey (colour false): 8-bit, pixel = round(127.5 + 127.5 value / R),
//    clamped, so -R -> 0, 0 -> 128, +R -> 255, whatever the convention
//    (inside is dark for inside negative, light for inside positive).
// NaN values take the centre (white, 128). tEXt: voxd:unit, voxd:range
// ("R unit"), voxd:sign ("inside negative"/"inside positive"), voxd:min and
// voxd:max (-R and +R with the unit), and voxd:grey (the formula) or the
// colour map's chunks. Throws Error(invalid_argument) for a null field or
// units_per_voxel not a positive finite number, and as value_section().
std::vector<std::uint8_t> sdf_section_png(const SdfRenderInput& input, int axis, std::int64_t index, bool colour,
                                          std::vector<PngText> text = {});

}  // namespace voxd
