// A section: one voxel layer across an axis, of the solid (coloured by wall
// thickness, or peeled) or of a value job's values.
#include "server/jobs/analyses/analysis_support.h"

#include <type_traits>
#include <variant>

#include "api/job_params.h"
#include "voxd/analysis/section.h"
#include "voxd/analysis/value_images.h"

namespace voxd::server {
namespace {

// The modes whose values are distances, "a or b".
std::string distance_modes() {
  std::string names;
  for (const api::JobMode* m : api::job_modes())
    if (m->distance_values()) names.append(names.empty() ? "" : " or ").append(m->name());
  return names;
}

// A value job's section shows its values (colour none or distance); colour
// thickness and peeled sections show the solid (nullopt).
std::optional<std::string> value_job_section(const AnalysisInput& in, std::int64_t layer) {
  const api::AnalysisRequest& r = in.request;
  const JobSnapshot& job = in.job;
  const std::optional<SdfRenderInput> field = sdf_input(in);
  if (r.colour == "distance" && !field)
    throw AnalysisRejected("colour=distance shows the distances of an " + distance_modes() + " job; this job's mode is " +
                           job.job->mode_name() + ": use colour none or thickness");
  if (!in.output.values || r.colour == "thickness" || r.slice_coloured()) return std::nullopt;
  // Values that are not an image (indices into a table): the section shows the solid.
  if (!job.job->mode->values_are_image()) return std::nullopt;
  if (r.peel > 0)
    throw AnalysisRejected("peel removes skin from the solid; a section of the job's values takes no peel "
                           "(use colour=thickness for the peeled solid)");
  const std::vector<PngText> text = image_text(in);
  if (field) return to_bytes(sdf_section_png(*field, r.axis, layer, r.colour == "distance", text));
  return std::visit(
      [&](const auto& v) {
        if constexpr (std::is_same_v<std::decay_t<decltype(v)>, DenseVolume<Rgba8>>)
          return to_bytes(colour_section_png(v, r.axis, layer, text));
        else
          return to_bytes(coverage_section_png(v, r.axis, layer, text));
      },
      *in.output.values);
}

class SectionAnalysis final : public JobAnalysisKind {
 public:
  api::AnalysisKind kind() const override { return api::AnalysisKind::section; }

  std::string compute(const AnalysisInput& in, const BitVolume& volume) const override {
    const api::AnalysisRequest& r = in.request;
    const std::int64_t layer = section_layer(r, in.job.grid);
    if (auto values = value_job_section(in, layer)) return std::move(*values);
    const std::optional<BitVolume> peeled_model = peeled_volume(r, volume);
    const BitVolume& model = peeled_model ? *peeled_model : volume;
    // An editor's next picture, redrawn while a parameter is dragged: encoded fast.
    if (r.slice_coloured())
      return to_bytes(slice_section_png(model, *slice_colours(in), r.axis, layer, image_text(in, true), 0,
                                        PngCompression::fast));
    JobThicknessMap map;
    if (r.colour == "thickness") map = job_thickness_map(volume, in.artifacts, in.control);
    return to_bytes(section_png(model, r.axis, layer, map.map.get(), image_text(in, true)));
  }

  bool streams_over_slabs(const api::AnalysisRequest& r) const override { return r.peel == 0 && r.colour == "none"; }
  bool shows_values(const api::AnalysisRequest& r) const override {
    return r.colour != "thickness" && !r.slice_coloured() && r.peel == 0;
  }

  std::string over_slabs(const AnalysisInput& in) const override {
    const api::AnalysisRequest& r = in.request;
    const JobSnapshot& job = in.job;
    const std::int64_t layer = section_layer(r, job.grid);
    if (in.output.values_rle && job.job->mode->values_are_image()) {
      // A coverage's grey levels, from its stored values, as value_job_section shows them.
      CoverageSectionGatherer section(job.grid, r.axis, layer);
      replay_values(in, [&](std::int64_t k0, const ValueVolume& slab) {
        std::visit(
            [&](const auto& v) {
              if constexpr (std::is_same_v<std::decay_t<decltype(v)>, DenseVolume<Rgba8>>)
                throw std::logic_error("a streamed job of colours");
              else
                section.add(k0, v);
            },
            slab);
      });
      return to_bytes(section.png(image_text(in)));
    }
    SectionGatherer section(job.grid, r.axis, layer);  // from the stored runs: the rows the plane cuts
    replay_runs(in, [&](std::int64_t k0, const RunSlab& slab) { section.add(k0, slab); });
    return to_bytes(section_png(section.take(), job.grid, r.axis, layer, image_text(in)));
  }

  // The image and its PNG, and a slab of runs.
  std::uint64_t over_slabs_memory(const api::AnalysisRequest& r, const Grid& grid) const override {
    return 2 * image_pixels(grid, r.axis) + run_slab_bytes(grid);
  }

  std::uint64_t whole_grid_bytes_per_voxel(const api::AnalysisRequest& r) const override {
    return r.colour == "thickness" ? 18 : 6;
  }

  // The kept mesh, turned, for a slice function's frame.
  std::uint64_t bytes_per_triangle(const api::AnalysisRequest& r) const override { return r.slice_coloured() ? 64 : 0; }

  std::string needs_whole_grid(const api::AnalysisRequest& r) const override {
    return r.peel > 0               ? "a section of the peeled model (peel)"
           : r.slice_coloured() ? "a section coloured by a slice function"
                                 : "a section coloured by wall thickness";
  }
};

}  // namespace

const JobAnalysisKind& section_analysis() {
  static const SectionAnalysis kind;
  return kind;
}

}  // namespace voxd::server
