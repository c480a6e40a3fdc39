// A shaded preview from one of six views: of the solid (coloured by wall
// thickness), a colour job's colours, or a distance field's zero level set.
#include "server/jobs/analyses/analysis_support.h"

#include <variant>

#include "api/job_params.h"
#include "server/jobs/analyses/slice_editing_cache.h"
#include "voxd/analysis/preview.h"
#include "voxd/analysis/value_images.h"

namespace voxd::server {
namespace {

// The request's size as the engine takes it: 0 for full size.
int max_side(const api::AnalysisRequest& r) { return static_cast<int>(r.size); }

class PreviewAnalysis final : public JobAnalysisKind {
 public:
  api::AnalysisKind kind() const override { return api::AnalysisKind::preview; }

  std::string compute(const AnalysisInput& in, const BitVolume& volume) const override {
    const api::AnalysisRequest& r = in.request;
    const View view = *parse_view(r.view);
    if (r.slice_coloured()) {
      // The rendering is the solid's whatever the function: kept for the next one.
      const std::unique_ptr<const SliceColours> colours = slice_colours(in);
      SliceEditingCache& cache = slice_editing_cache();
      std::shared_ptr<const PreviewImage> rendered = cache.preview(in.job.id, view);
      if (!rendered) {
        rendered = std::make_shared<const PreviewImage>(render_preview(volume, view, 0));
        cache.keep_preview(in.job.id, view, rendered);
      }
      return to_bytes(slice_preview_png(*rendered, volume.grid(), *colours, view, image_text(in), 0, max_side(r),
                                        PngCompression::fast));  // redrawn while a parameter is dragged
    }
    // A distance field's surface is its zero level set, rendered directly.
    if (const auto field = sdf_input(in); field && r.colour == "none")
      return to_bytes(sdf_preview_png(*field, view, image_text(in), 0, 1, max_side(r)));
    // A colour job's preview shows its colours.
    const std::shared_ptr<const ValueVolume>& values = in.output.values;
    if (values && std::holds_alternative<DenseVolume<Rgba8>>(*values) && r.colour == "none")
      return to_bytes(colour_preview_png(volume, std::get<DenseVolume<Rgba8>>(*values), view, image_text(in), 0,
                                         max_side(r)));
    JobThicknessMap map;
    if (r.colour == "thickness") map = job_thickness_map(volume, in.artifacts, in.control);
    return to_bytes(preview_png(volume, view, map.map.get(), image_text(in), 0, max_side(r)));
  }

  bool streams_over_slabs(const api::AnalysisRequest& r) const override { return r.colour == "none"; }
  bool shows_values(const api::AnalysisRequest& r) const override { return r.colour == "none"; }

  // Two passes over the stored runs: the visible voxels, then their
  // normals (the cost the runs', not the grid's bits').
  std::string over_slabs(const AnalysisInput& in) const override {
    const Grid& grid = in.job.grid;
    const View view = *parse_view(in.request.view);
    PreviewRenderer preview(grid, view, 0, max_side(in.request));  // shrunk as it is made
    replay_runs(in, [&](std::int64_t k0, const RunSlab& slab) { preview.find(k0, slab); }, 0.0, 0.5);
    replay_runs(in, [&](std::int64_t k0, const RunSlab& slab) { preview.shade(k0, slab); }, 0.5, 1.0);
    return to_bytes(preview_png(preview.take(), grid, view, image_text(in), max_side(in.request)));
  }

  // The depths, then at full size (no `size`) the visible voxels, normals
  // (raw and smoothed), shades, pixels sorted by layer, the RGB image and
  // its PNG; shrunk, those of the blocks only (9 raw normals a block); a
  // slab of runs and the seam's copy of its last layers.
  std::uint64_t over_slabs_memory(const api::AnalysisRequest& r, const Grid& grid) const override {
    const std::uint64_t pixels = image_pixels(grid, parse_view(r.view)->axis);
    const std::uint64_t per_pixel = r.size == 0 ? 8 + 4 + 12 + 12 + 4 + 4 + 3 + 3 : 4;
    return per_pixel * pixels + 2 * run_slab_bytes(grid) +
           (r.size == 0 ? 0 : (8 + 12 + 4 + 8 + 9 * (12 + 4) + 3 + 3) * r.size * r.size);
  }

  std::uint64_t whole_grid_bytes_per_voxel(const api::AnalysisRequest& r) const override {
    return r.colour == "thickness" ? 18 : 6;
  }

  // The kept mesh, turned, for a slice function's frame.
  std::uint64_t bytes_per_triangle(const api::AnalysisRequest& r) const override { return r.slice_coloured() ? 64 : 0; }

  std::string needs_whole_grid(const api::AnalysisRequest& r) const override {
    return r.slice_coloured() ? "a preview coloured by a slice function" : "a preview coloured by wall thickness";
  }
};

}  // namespace

const JobAnalysisKind& preview_analysis() {
  static const PreviewAnalysis kind;
  return kind;
}

}  // namespace voxd::server
