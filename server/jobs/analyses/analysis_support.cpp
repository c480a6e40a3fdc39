#include "server/jobs/analyses/analysis_support.h"

#include <algorithm>
#include <climits>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "voxd/analysis/section.h"
#include "voxd/analysis/skin_removal.h"
#include "voxd/encode/rle_slabs.h"
#include "api/job_params.h"
#include "server/jobs/job_store.h"
#include "server/jobs/analyses/slice_editing_cache.h"
#include "server/jobs/kept_mesh.h"
#include "voxd/transform.h"
#include "voxd/error.h"

namespace voxd::server {

std::string to_bytes(const std::vector<std::uint8_t>& v) { return std::string(v.begin(), v.end()); }

std::vector<PngText> image_text(const AnalysisInput& in, bool with_peel) {
  std::vector<PngText> text = {{"voxd:job", in.job.id}};
  const api::AnalysisRequest& r = in.request;
  if (with_peel && r.peel > 0)
    text.push_back({"voxd:peeled", std::to_string(r.peel) + " layers (" + to_string(r.peel_metric) + ")"});
  return text;
}

std::optional<BitVolume> peeled_volume(const api::AnalysisRequest& r, const BitVolume& volume) {
  if (r.peel <= 0) return std::nullopt;
  return peeled(peel_depth(volume, 0, r.peel_metric),
                static_cast<std::uint32_t>(std::min<std::int64_t>(r.peel, UINT32_MAX)));
}

std::uint64_t run_slab_bytes(const Grid& grid) {
  const auto rows = static_cast<std::uint64_t>(grid.dims.y) * static_cast<std::uint64_t>(grid.dims.z);
  const std::uint64_t runs = rows * static_cast<std::uint64_t>((grid.dims.x + 1) / 2);
  return 8 * std::min<std::uint64_t>(runs, kRunSlabRuns) + 4 * std::min<std::uint64_t>(rows, kRunSlabRuns);
}

void replay_runs(const AnalysisInput& in, const RunSlabConsumer& consume, double from, double to) {
  if (!in.output.rle) throw std::logic_error("a streamed job's analysis without its stored volume");
  const Grid& grid = in.job.grid;
  JobControl* control = in.control;
  const double layers_total = static_cast<double>(grid.dims.z);
  read_rle_run_slabs(*in.output.rle->open(), grid.dims.z,
                     [&](std::int64_t k0, const RunSlab& slab) {
                       if (control) control->check_cancelled();
                       consume(k0, slab);
                       const double done = static_cast<double>(k0 + slab.grid().dims.z) / layers_total;
                       if (control) control->set_progress(from + (to - from) * done);
                     },
                     kStoredSlabLimits, 0);
}

void replay_values(const AnalysisInput& in, const ValueSlabConsumer& consume) {
  if (!in.output.values_rle) throw std::logic_error("a streamed job's section of values without its stored values");
  const Grid& grid = in.job.grid;
  JobControl* control = in.control;
  const double slabs_total = static_cast<double>(grid.dims.z);
  read_rle_value_slabs(*in.output.values_rle->open(), replay_value_slab_layers(grid),
                       [&](std::int64_t k0, const ValueVolume& slab) {
                         if (control) control->check_cancelled();
                         consume(k0, slab);
                         if (control) control->set_progress(static_cast<double>(k0 + grid_of(slab).dims.z) / slabs_total);
                       },
                       kStoredSlabLimits);
}

std::int64_t section_layer(const api::AnalysisRequest& r, const Grid& g) {
  if (r.coordinate) {
    try {
      return section_index(g, r.axis, *r.coordinate);
    } catch (const Error& e) {
      throw AnalysisRejected(e.what());
    }
  }
  if (*r.index >= g.dims[r.axis])
    throw AnalysisRejected("index must be an integer from 0 to " + std::to_string(g.dims[r.axis] - 1) + " along " +
                           std::string(1, "xyz"[r.axis]));
  return *r.index;
}

std::string radiography_result(const AnalysisInput& in, const ThicknessImage& image) {
  using nlohmann::json;
  const api::AnalysisRequest& r = in.request;
  const Grid& grid = in.job.grid;
  const RadiographyMeasure m = r.measure;
  const PngScale scale = radiography_scale(r, grid);
  if (r.format == "json") {
    const ThicknessStats s = thickness_stats(values_of(image, m), 32);
    json histogram = json::array();
    for (std::uint64_t n : s.histogram) histogram.push_back(n);
    const double k = scale.per_value;
    return json{{"axis", std::string(1, "xyz"[r.axis])}, {"measure", to_string(r.measure)}, {"unit", scale.unit},
                {"voxel_size", grid.voxel_size}, {"width", image.width}, {"height", image.height}, {"rays", s.rays},
                {"min", s.min * k}, {"max", s.max * k}, {"mean", s.mean * k},
                {"p5", s.p5 * k}, {"p50", s.p50 * k}, {"p95", s.p95 * k},
                {"histogram", {{"min", s.min * k}, {"bin_width", s.bin_width * k}, {"counts", histogram}}}}
        .dump();
  }
  return to_bytes(radiography_png(image, r.axis, m, r.format == "png", scale, image_text(in, true)));
}

std::optional<SdfRenderInput> sdf_input(const AnalysisInput& in) {
  if (!in.output.values) return std::nullopt;
  return in.job.job->mode->distance_field(*in.job.job, *in.output.values);
}

std::unique_ptr<const SliceColours> slice_colours(const AnalysisInput& in) {
  const api::AnalysisRequest& r = in.request;
  if (!r.slice) throw std::logic_error("colour=slice without its slice function");
  if (in.job.job->mode->voxel_aspect(*in.job.job) != glm::dvec3(1.0))
    throw AnalysisRejected("colour=slice colours a solid of cubic voxels as a slice job would; this job's " +
                           std::string(in.job.job->mode_name()) + " voxels are not cubes");
  SliceEditingCache& cache = slice_editing_cache();
  std::optional<SliceFrame> frame = cache.frame(in.job.id, r.slice->axis);
  if (!frame) {
    const auto kept = in.artifacts.load(kKeptMeshKey);
    if (!kept)
      throw AnalysisRejected("this job kept no mesh to place the slice function's frame on (it ran before the service "
                             "kept its jobs' meshes): submit it again");
    KeptMesh k = decode_kept_mesh(*kept);
    rotate_mesh(k.mesh, k.rotation);  // into the grid's frame, exactly as the job turned it
    frame = make_slice_frame(k.mesh, r.slice->axis);
    cache.keep_frame(in.job.id, r.slice->axis, *frame);
  }
  return std::make_unique<const SliceColours>(*r.slice, *frame, in.job.grid);
}

std::uint64_t image_pixels(const Grid& grid, int axis) {
  return static_cast<std::uint64_t>(axis == 0 ? grid.dims.y : grid.dims.x) *
         static_cast<std::uint64_t>(axis == 2 ? grid.dims.y : grid.dims.z);
}

}  // namespace voxd::server
