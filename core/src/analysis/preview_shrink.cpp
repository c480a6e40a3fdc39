// A preview of a huge grid shown at a sensible size (voxd/analysis/preview.h):
// a block of rendered pixels becomes one, showing the block's nearest
// visible voxel. Nearest, not the block's mean or its first pixel: a thin
// wall or rib seen edge-on covers only some of a block's pixels and would
// vanish or flicker in a sampled image; the nearest voxel keeps it, the way
// a max-pooled depth image keeps the nearest surface.
#include <algorithm>

#include "voxd/analysis/preview.h"
#include "voxd/error.h"

namespace voxd {

int shrink_factor(int width, int height, int max_side) {
  if (max_side <= 0) return 1;
  const int longest = std::max(width, height);
  return std::max(1, (longest + max_side - 1) / max_side);
}

PreviewImage shrink_preview(const PreviewImage& image, const Grid& grid, View view, int factor) {
  if (factor < 1) throw Error(ErrorCode::invalid_argument, "preview: a shrink factor must be at least 1");
  if (factor == 1) return image;
  const glm::i64vec3 d = grid.dims;
  // A visible voxel's place along the view axis, larger nearer the camera.
  auto nearness = [&](std::int64_t index) {
    const std::int64_t at = view.axis == 0 ? index % d.x : view.axis == 1 ? (index / d.x) % d.y : index / (d.x * d.y);
    return view.from_positive ? at : -at;
  };
  PreviewImage out;
  out.width = (image.width + factor - 1) / factor;
  out.height = (image.height + factor - 1) / factor;
  out.block = image.block * factor;
  const auto pixels = static_cast<std::size_t>(out.width) * static_cast<std::size_t>(out.height);
  out.voxel.assign(pixels, -1);
  out.shade.assign(pixels, 0.0f);
  out.normal.assign(pixels, glm::vec3(0.0f));
  for (int row = 0; row < out.height; ++row)
    for (int col = 0; col < out.width; ++col) {
      std::size_t best = SIZE_MAX;
      std::int64_t best_nearness = 0;
      for (int r = row * factor; r < std::min(image.height, (row + 1) * factor); ++r)
        for (int c = col * factor; c < std::min(image.width, (col + 1) * factor); ++c) {
          const std::size_t p = static_cast<std::size_t>(r) * static_cast<std::size_t>(image.width) + static_cast<std::size_t>(c);
          if (image.voxel[p] < 0) continue;
          const std::int64_t n = nearness(image.voxel[p]);
          if (best == SIZE_MAX || n > best_nearness) {
            best = p;
            best_nearness = n;
          }
        }
      if (best == SIZE_MAX) continue;
      const std::size_t q = static_cast<std::size_t>(row) * static_cast<std::size_t>(out.width) + static_cast<std::size_t>(col);
      out.voxel[q] = image.voxel[best];
      out.shade[q] = image.shade[best];
      out.normal[q] = image.normal[best];
    }
  return out;
}

}  // namespace voxd
