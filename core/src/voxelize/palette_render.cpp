// Rendering palettes: per voxel, the first display object whose threshold
// the similarity reaches. See voxd/voxelize/palette_render.h.
#include "voxd/voxelize/palette_render.h"

#include <array>
#include <cmath>

#include "voxd/error.h"

namespace voxd {

DenseVolume<std::uint8_t> render_palette(const DenseVolume<std::uint8_t>& element,
                                         const DenseVolume<std::uint8_t>& similarity, const RenderPalette& render) {
  if (element.grid().dims != similarity.grid().dims)
    throw Error(ErrorCode::invalid_argument, "palette element and similarity volumes differ in size");
  // One lookup table over (element, similarity byte): the rules are applied
  // 256 x 256 times at most, not once per voxel.
  std::vector<std::array<std::uint8_t, 256>> table(256);
  for (std::size_t e = 0; e < 256; ++e)
    for (int b = 0; b < 256; ++b) {
      std::uint8_t shown = 0;
      if (e < render.by_element.size())
        for (const DisplayChoice& c : render.by_element[e])
          // Compare in bytes, as stored: D reached when round(255 D) <= byte.
          if (std::lround(255.0 * c.min_similarity) <= b) {
            shown = c.object;
            break;
          }
      table[e][static_cast<std::size_t>(b)] = shown;
    }
  DenseVolume<std::uint8_t> out(element.grid(), 0);
  const auto& el = element.values();
  const auto& si = similarity.values();
  auto& o = out.values();
  for (std::size_t i = 0; i < el.size(); ++i) o[i] = table[el[i]][si[i]];
  return out;
}

}  // namespace voxd
