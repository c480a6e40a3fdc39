#include "server/jobs/job_analyses.h"
#include "server/jobs/job_manager.h"
#include "server/jobs/job_store.h"

#include <climits>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <mutex>

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "api/analysis_json.h"
#include "api/job_params.h"
#include "voxd/analysis/analysis.h"
#include "voxd/analysis/analysis_images.h"
#include "voxd/byte_sink.h"
#include "voxd/error.h"
#include "voxd/analysis/preview.h"
#include "voxd/analysis/radiography.h"
#include "voxd/analysis/sdf_render.h"
#include "voxd/analysis/section.h"
#include "voxd/analysis/skin_removal.h"
#include "voxd/analysis/value_images.h"
#include "voxd/encode/rle_slabs.h"
#include "voxd/encode/volume_format.h"
#include "voxd/analysis/components.h"
#include "voxd/analysis/mass_properties.h"
#include "voxd/voxelize/streamed.h"

namespace voxd::server {
namespace {

using nlohmann::json;
using api::AnalysisKind;
using api::AnalysisRequest;


// One mutex per (scope, key) being computed, dropped when nobody holds it.
class KeyLocks {
 public:
  std::shared_ptr<std::mutex> get(const std::string& name) {
    std::lock_guard guard(mutex_);
    for (auto it = locks_.begin(); it != locks_.end();) it = it->second.expired() ? locks_.erase(it) : std::next(it);
    std::shared_ptr<std::mutex> lock = locks_[name].lock();
    if (!lock) {
      lock = std::make_shared<std::mutex>();
      locks_[name] = lock;
    }
    return lock;
  }

 private:
  std::mutex mutex_;
  std::map<std::string, std::weak_ptr<std::mutex>> locks_;
};

std::shared_ptr<std::mutex> key_lock(const ArtifactAccess& artifacts, const std::string& key) {
  static KeyLocks locks;
  return locks.get(artifacts.scope + "/" + key);
}

std::string to_bytes(const std::vector<std::uint8_t>& v) { return std::string(v.begin(), v.end()); }


std::string analysis_json(const AnalysisRequest& r, const JobSnapshot& job, const BitVolume& volume,
                          const ArtifactAccess& artifacts, JobControl* control) {
  AnalysisOptions options;
  if (r.cleanup != "none") options.cleanup = CleanupOptions{true, true, r.cleanup == "sheets"};
  options.thickness = r.thickness;
  options.skin = r.skin;
  options.peel = r.peel_metric;
  options.min_wall_voxels = r.min_wall.value_or(0) / job.grid.voxel_size;
  options.max_wall_voxels = r.max_wall.value_or(0) / job.grid.voxel_size;
  std::shared_ptr<const DenseVolume<float>> map;
  const bool map_first = r.thickness && !options.cleanup;
  if (map_first) {
    // The thickness map takes most of the time: most of the bar.
    const NestedSpan map_share(control, 0.0, 0.8);
    map = job_thickness_map(volume, artifacts, control);
    options.thickness_map = map.get();
  }
  const NestedSpan report_share(control, map_first ? 0.8 : 0.0, 1.0);
  const AnalysisReport report = analyze_volume(volume, options, control);
  return api::analysis_to_json(report, job.grid, job.mesh, job.mesh_mass).dump();
}

// The volume after r.peel layers of skin removal, or null for none.
std::optional<BitVolume> peeled_volume(const AnalysisRequest& r, const BitVolume& volume) {
  if (r.peel <= 0) return std::nullopt;
  const PeelMetric metric = r.peel_metric;
  return peeled(peel_depth(volume, 0, metric), static_cast<std::uint32_t>(std::min<std::int64_t>(r.peel, UINT32_MAX)));
}

std::string radiography_result(const AnalysisRequest& r, const JobSnapshot& job, const ThicknessImage& image) {
  const RadiographyMeasure m = r.measure;
  const PngScale scale = radiography_scale(r, job.grid);
  if (r.format == "json") {
    const ThicknessStats s = thickness_stats(values_of(image, m), 32);
    json histogram = json::array();
    for (std::uint64_t n : s.histogram) histogram.push_back(n);
    const double k = scale.per_value;
    return json{{"axis", std::string(1, "xyz"[r.axis])}, {"measure", to_string(r.measure)}, {"unit", scale.unit},
                {"voxel_size", job.grid.voxel_size}, {"width", image.width}, {"height", image.height}, {"rays", s.rays},
                {"min", s.min * k}, {"max", s.max * k}, {"mean", s.mean * k},
                {"p5", s.p5 * k}, {"p50", s.p50 * k}, {"p95", s.p95 * k},
                {"histogram", {{"min", s.min * k}, {"bin_width", s.bin_width * k}, {"counts", histogram}}}}
        .dump();
  }
  std::vector<PngText> text = {{"voxd:job", job.id}};
  if (r.peel > 0) text.push_back({"voxd:peeled", std::to_string(r.peel) + " layers (" + to_string(r.peel_metric) + ")"});
  return to_bytes(radiography_png(image, r.axis, m, r.format == "png", scale, text));
}

ThicknessImage job_radiography(const AnalysisRequest& r, const BitVolume& original) {
  const std::optional<BitVolume> peeled_model = peeled_volume(r, original);
  return radiography(peeled_model ? *peeled_model : original, r.axis);
}

// Replays a streamed job's stored volume slab by slab (kReplaySlabBytes),
// with progress over the slabs and cancellation between them.
// The progress runs over [from, to] (a request of two passes takes half each).
void replay(const JobOutput& output, const Grid& grid, JobControl* control, const BitSlabConsumer& consume,
            double from = 0.0, double to = 1.0) {
  if (!output.rle) throw std::logic_error("a streamed job's analysis without its stored volume");
  const double slabs_total = static_cast<double>(grid.dims.z);
  read_rle_bit_slabs(output.rle->bytes(), replay_bit_slab_layers(grid),
                     [&](std::int64_t k0, const BitVolume& slab) {
                       if (control) control->check_cancelled();
                       consume(k0, slab);
                       const double done = static_cast<double>(k0 + slab.grid().dims.z) / slabs_total;
                       if (control) control->set_progress(from + (to - from) * done);
                     },
                     kStoredSlabLimits);
}

// The same for a streamed job's stored values.
void replay_values(const JobOutput& output, const Grid& grid, JobControl* control, const ValueSlabConsumer& consume) {
  if (!output.values_rle) throw std::logic_error("a streamed job's section of values without its stored values");
  const double slabs_total = static_cast<double>(grid.dims.z);
  read_rle_value_slabs(output.values_rle->bytes(), replay_value_slab_layers(grid),
                       [&](std::int64_t k0, const ValueVolume& slab) {
                         if (control) control->check_cancelled();
                         consume(k0, slab);
                         if (control) control->set_progress(static_cast<double>(k0 + grid_of(slab).dims.z) / slabs_total);
                       },
                       kStoredSlabLimits);
}

// The analysis of a streamed job's volume: mass properties, parts and voids
// from its slabs; the bytes analysis_json makes for the same request in memory.
std::string streamed_analysis_json(const AnalysisRequest& r, const JobSnapshot& job, const JobOutput& output,
                                   JobControl* control) {
  VoxelMassAccumulator mass(job.grid);
  ComponentLabeller components(job.grid);
  replay(output, job.grid, control, [&](std::int64_t k0, const BitVolume& slab) {
    mass.add(k0, slab);
    components.add(k0, slab);
  });
  AnalysisReport report;
  report.voxels = mass.result();
  report.components = components.finish();
  report.peel = r.peel_metric;
  return api::analysis_to_json(report, job.grid, job.mesh, job.mesh_mass).dump();
}

std::int64_t section_layer(const AnalysisRequest& r, const Grid& g) {
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

// The thickness map in the unit asked for: voxels as computed, or model
// units (times the voxel size).
DenseVolume<float> thickness_in(DenseVolume<float> map, const std::string& unit) {
  if (unit == "model") {
    const auto h = static_cast<float>(map.grid().voxel_size);
    for (float& v : map.values()) v *= h;
  }
  return map;
}

// The modes whose values are distances, "a or b".
std::string distance_modes() {
  std::string names;
  for (const api::JobMode* m : api::job_modes())
    if (m->distance_values()) names.append(names.empty() ? "" : " or ").append(m->name());
  return names;
}

// A distance field's values and how to read them (its convention and units
// come from the job's mode and options); nullopt for other jobs.
std::optional<SdfRenderInput> sdf_input(const JobSnapshot& job, const JobOutput& output) {
  if (!output.values) return std::nullopt;
  return job.job->mode->distance_field(*job.job, *output.values);
}

// A value job's section shows its values (colour none or
// distance); colour thickness and peeled sections show the solid.
std::optional<std::string> value_job_section(const AnalysisRequest& r, const JobSnapshot& job, const JobOutput& output,
                                             std::int64_t layer, const std::vector<PngText>& text) {
  const std::optional<SdfRenderInput> field = sdf_input(job, output);
  if (r.colour == "distance" && !field)
    throw AnalysisRejected("colour=distance shows the distances of an " + distance_modes() + " job; this job's mode is " +
                           job.job->mode_name() + ": use colour none or thickness");
  if (!output.values || r.colour == "thickness") return std::nullopt;
  // Values that are not an image (indices into a table): the section shows the solid.
  if (!job.job->mode->values_are_image()) return std::nullopt;
  if (r.peel > 0)
    throw AnalysisRejected("peel removes skin from the solid; a section of the job's values takes no peel "
                           "(use colour=thickness for the peeled solid)");
  if (field) return to_bytes(sdf_section_png(*field, r.axis, layer, r.colour == "distance", text));
  return std::visit(
      [&](const auto& v) {
        if constexpr (std::is_same_v<std::decay_t<decltype(v)>, DenseVolume<Rgba8>>)
          return to_bytes(colour_section_png(v, r.axis, layer, text));
        else
          return to_bytes(coverage_section_png(v, r.axis, layer, text));
      },
      *output.values);
}

std::string thickness_volume(const AnalysisRequest& r, const BitVolume& volume, const ArtifactAccess& artifacts,
                             JobControl* control) {
  const DenseVolume<float> map =
      thickness_in(*job_thickness_map(volume, artifacts, control, r.thickness_measure), r.unit);
  VectorSink out;
  if (r.format == "rle") {
    write_rle(map, out);
  } else if (r.format == "raw") {
    write_raw(map, out);
  } else {
    write_nrrd(map, std::string(to_string(r.thickness_measure)) + " thickness (" + (r.unit == "model" ? "model units" : "voxels") + ")",
               out);
  }
  return to_bytes(out.data);
}

}  // namespace

PngScale radiography_scale(const AnalysisRequest& r, const Grid& g) {
  return r.unit == "model" ? PngScale{g.voxel_size, "model units"} : PngScale{1.0, "voxel"};
}

bool streams_over_slabs(const AnalysisRequest& r) {
  switch (r.kind) {
    case AnalysisKind::analysis: return r.cleanup == "none" && !r.thickness && !r.skin;
    case AnalysisKind::radiography: return r.peel == 0;
    case AnalysisKind::section: return r.peel == 0 && r.colour == "none";
    case AnalysisKind::preview: return r.colour == "none";
    case AnalysisKind::thickness: return false;
  }
  return false;
}

std::uint64_t whole_grid_memory(const AnalysisRequest& r, const Grid& grid) {
  return bit_volume_bytes(grid.dims) + estimate_analysis_memory(r, grid);
}

std::string whole_grid_refusal(const AnalysisRequest& r, const Grid& grid, std::uint64_t max_job_memory) {
  // The largest cube whose bits and analysis fit: per-voxel cost from two
  // sizes (the estimate is affine in the voxel count).
  Grid unit;
  unit.dims = {1, 1, 1};
  Grid two = unit;
  two.dims = {1024, 1024, 1024};
  const std::uint64_t fixed = whole_grid_memory(r, unit);
  const double per_voxel = static_cast<double>(whole_grid_memory(r, two) - fixed) / static_cast<double>(two.voxel_count());
  const double largest = max_job_memory > fixed ? static_cast<double>(max_job_memory - fixed) / per_voxel : 0.0;
  const auto largest_voxels = static_cast<std::uint64_t>(largest);
  const auto side = static_cast<std::uint64_t>(std::cbrt(largest));
  std::string what;
  switch (r.kind) {
    case AnalysisKind::analysis:
      what = r.thickness ? "wall thickness" : r.skin ? "skin removal" : "clean-up";
      what += " (in the analysis)";
      break;
    case AnalysisKind::radiography: what = "a radiography of the peeled model (peel)"; break;
    case AnalysisKind::section: what = r.peel > 0 ? "a section of the peeled model (peel)" : "a section coloured by wall thickness"; break;
    case AnalysisKind::preview: what = "a preview coloured by wall thickness"; break;
    case AnalysisKind::thickness: what = std::string("the ") + to_string(r.thickness_measure) + " thickness volume"; break;
  }
  return what + " needs the whole grid in memory, about " + std::to_string(whole_grid_memory(r, grid) >> 20) +
         " MiB for this job's " + std::to_string(grid.dims.x) + " x " + std::to_string(grid.dims.y) + " x " +
         std::to_string(grid.dims.z) + " grid; the largest grid it accepts here is " + std::to_string(largest_voxels) +
         " voxels (about " + std::to_string(side) + "^3, per-job memory " + std::to_string(max_job_memory >> 20) +
         " MiB). This job's volume was made slab by slab: radiography, sections and shaded previews (without peel "
         "or thickness colours) and the analysis with thickness=false&skin=false stream over it at any size";
}

bool streams_over_slabs(const AnalysisRequest& r, const api::JobParams& params) {
  const bool shows_distances = (r.kind == AnalysisKind::preview && r.colour == "none") ||
                               (r.kind == AnalysisKind::section && r.colour != "thickness" && r.peel == 0);
  return streams_over_slabs(r) && !(params.mode->distance_values() && shows_distances);
}

std::uint64_t analysis_memory_on_job(const AnalysisRequest& r, const api::JobParams& params, const Grid& grid,
                                     bool streamed_job, std::uint64_t max_job_memory) {
  if (!streamed_job) return estimate_analysis_memory(r, grid);
  if (streams_over_slabs(r, params)) return estimate_analysis_memory(r, grid, true);
  std::uint64_t whole = whole_grid_memory(r, grid);
  if (const std::optional<ValueVolume> type = params.value_type())  // its values are read whole too
    whole += grid.voxel_count() * std::visit([]<typename T>(const DenseVolume<T>&) { return sizeof(T); }, *type);
  if (whole > max_job_memory) throw Error(ErrorCode::limit_exceeded, whole_grid_refusal(r, grid, max_job_memory));
  return whole;
}

std::uint64_t estimate_analysis_memory(const AnalysisRequest& r, const Grid& grid, bool over_slabs) {
  constexpr std::uint64_t kImagesAndReports = std::uint64_t{16} << 20;
  if (over_slabs) {
    // One replayed slab, and for a radiography its four maps of 32 bits a
    // pixel, one layer of bits and the PNG; a section's image and PNG; a
    // preview's visible voxels, depths, normals (raw and smoothed), shades,
    // pixels sorted by layer, the RGB image and its PNG, and three layers.
    const std::uint64_t slab = kReplaySlabBytes;
    const int axis = r.kind == AnalysisKind::preview ? parse_view(r.view)->axis : r.axis;
    const std::uint64_t pixels = r.kind == AnalysisKind::analysis ? 0
                                 : static_cast<std::uint64_t>(axis == 0 ? grid.dims.y : grid.dims.x) *
                                       static_cast<std::uint64_t>(axis == 2 ? grid.dims.y : grid.dims.z);
    const std::uint64_t layer = bit_volume_bytes({grid.dims.x, grid.dims.y, 1});
    switch (r.kind) {
      case AnalysisKind::radiography: return slab + (4 * 4 + 2 + 4) * pixels + layer + kImagesAndReports;
      case AnalysisKind::preview: return slab + (8 + 4 + 12 + 12 + 4 + 4 + 3 + 3) * pixels + 3 * layer + kImagesAndReports;
      default: return slab + 2 * pixels + kImagesAndReports;
    }
  }
  const std::uint64_t voxels = grid.voxel_count();
  const bool thickness = r.kind == AnalysisKind::thickness || (r.kind == AnalysisKind::analysis && r.thickness) ||
                         r.colour == "thickness";
  // The distance transform and the thickness map (floats), the labels of
  // parts and voids or the peel depths (32 bits a voxel), bit copies.
  std::uint64_t per_voxel = thickness ? 18 : 6;
  // The map in the asked unit, the encoded volume and its kept copy.
  if (r.kind == AnalysisKind::thickness) per_voxel += 12;
  return per_voxel * voxels + kImagesAndReports;
}

ArtifactAccess artifacts_of(JobManager& jobs, const std::string& id) {
  return {id, [&jobs, id](const std::string& key) { return jobs.load_artifact(id, key); },
          [&jobs, id](const std::string& key, const std::string& bytes) { jobs.save_artifact(id, key, bytes); }};
}

// One kept map per measure; the names changed when the report moved from
// local to wall thickness, so a map kept by an older replica is never read
// as the other measure.
const char* thickness_map_key(api::ThicknessMeasure m) {
  return m == api::ThicknessMeasure::wall ? "wall-thickness-map.f32" : "local-thickness-map.f32";
}

std::shared_ptr<const DenseVolume<float>> job_thickness_map(const BitVolume& volume, const ArtifactAccess& artifacts,
                                                            JobControl* control, api::ThicknessMeasure measure) {
  if (measure == api::ThicknessMeasure::wall && artifacts.wall_map && artifacts.wall_map->grid().dims == volume.grid().dims)
    return artifacts.wall_map;
  const char* key = thickness_map_key(measure);
  const auto lock = key_lock(artifacts, key);
  std::lock_guard guard(*lock);
  auto map = std::make_shared<DenseVolume<float>>(volume.grid(), 0.0f);
  if (auto kept = artifacts.load(key); kept && kept->size() == map->values().size() * sizeof(float)) {
    std::memcpy(map->values().data(), kept->data(), kept->size());
    return map;
  }
  const auto t0 = std::chrono::steady_clock::now();
  *map = measure == api::ThicknessMeasure::wall ? wall_thickness(volume, 0, control) : local_thickness(volume, 0, control);
  spdlog::info("job {}: {} thickness computed in {:.3f} s", artifacts.scope, to_string(measure),
               std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  artifacts.save(key, std::string(reinterpret_cast<const char*>(map->values().data()),
                                  map->values().size() * sizeof(float)));
  return map;
}

namespace {

// A streamed job's request that streams, answered from its slabs with the
// bytes the in-memory path gives.
std::string over_slabs(const AnalysisRequest& r, const JobSnapshot& job, const JobOutput& output, JobControl* control) {
  switch (r.kind) {
    case AnalysisKind::analysis: return streamed_analysis_json(r, job, output, control);
    case AnalysisKind::radiography: {
      RadiographyAccumulator image(job.grid, r.axis);
      replay(output, job.grid, control, [&](std::int64_t k0, const BitVolume& slab) { image.add(k0, slab); });
      return radiography_result(r, job, image.take());
    }
    case AnalysisKind::section: {
      const std::int64_t layer = section_layer(r, job.grid);
      if (output.values_rle && job.job->mode->values_are_image()) {
        // A coverage's grey levels, from its stored values, as value_job_section shows them.
        CoverageSectionGatherer section(job.grid, r.axis, layer);
        replay_values(output, job.grid, control, [&](std::int64_t k0, const ValueVolume& slab) {
          std::visit(
              [&](const auto& v) {
                if constexpr (std::is_same_v<std::decay_t<decltype(v)>, DenseVolume<Rgba8>>)
                  throw std::logic_error("a streamed job of colours");
                else
                  section.add(k0, v);
              },
              slab);
        });
        return to_bytes(section.png({{"voxd:job", job.id}}));
      }
      SectionGatherer section(job.grid, r.axis, layer);
      replay(output, job.grid, control, [&](std::int64_t k0, const BitVolume& slab) { section.add(k0, slab); });
      return to_bytes(section_png(section.take(), job.grid, r.axis, layer, {{"voxd:job", job.id}}));
    }
    case AnalysisKind::preview: {
      // Two passes: the visible voxels, then their normals.
      const View view = *parse_view(r.view);
      PreviewRenderer preview(job.grid, view);
      replay(output, job.grid, control, [&](std::int64_t k0, const BitVolume& slab) { preview.find(k0, slab); }, 0.0, 0.5);
      replay(output, job.grid, control, [&](std::int64_t k0, const BitVolume& slab) { preview.shade(k0, slab); }, 0.5, 1.0);
      return to_bytes(preview_png(preview.take(), job.grid, view, {{"voxd:job", job.id}}));
    }
    default: throw std::logic_error(std::string("a ") + to_string(r.kind) + " request does not stream");
  }
}

}  // namespace

AnalysisResult job_analysis(const AnalysisRequest& r, const JobSnapshot& job, const JobOutput& output,
                            const ArtifactAccess& artifacts, JobControl* control) {
  const std::string key = r.artifact_key();
  if (auto kept = artifacts.load(key)) return {std::move(*kept), true};
  const auto lock = key_lock(artifacts, key);
  std::lock_guard guard(*lock);
  if (auto kept = artifacts.load(key)) return {std::move(*kept), true};  // computed while we waited
  if (!output.solid) {
    std::string bytes = over_slabs(r, job, output, control);
    artifacts.save(key, bytes);
    return {std::move(bytes), false};
  }
  const BitVolume& volume = *output.solid;
  std::string bytes;
  switch (r.kind) {
    case AnalysisKind::analysis: bytes = analysis_json(r, job, volume, artifacts, control); break;
    case AnalysisKind::radiography: bytes = radiography_result(r, job, job_radiography(r, volume)); break;
    case AnalysisKind::section: {
      const std::int64_t layer = section_layer(r, job.grid);
      if (auto values = value_job_section(r, job, output, layer, {{"voxd:job", job.id}})) {
        bytes = std::move(*values);
        break;
      }
      std::shared_ptr<const DenseVolume<float>> map;
      if (r.colour == "thickness") map = job_thickness_map(volume, artifacts, control);
      const std::optional<BitVolume> peeled_model = peeled_volume(r, volume);
      std::vector<PngText> text = {{"voxd:job", job.id}};
      if (r.peel > 0) text.push_back({"voxd:peeled", std::to_string(r.peel) + " layers (" + to_string(r.peel_metric) + ")"});
      bytes = to_bytes(section_png(peeled_model ? *peeled_model : volume, r.axis, layer, map.get(), text));
      break;
    }
    case AnalysisKind::preview: {
      // A distance field's surface is its zero level set, rendered directly.
      if (const auto field = sdf_input(job, output); field && r.colour == "none") {
        bytes = to_bytes(sdf_preview_png(*field, *parse_view(r.view), {{"voxd:job", job.id}}));
        break;
      }
      // A colour job's preview shows its colours.
      if (output.values && std::holds_alternative<DenseVolume<Rgba8>>(*output.values) && r.colour == "none") {
        bytes = to_bytes(colour_preview_png(volume, std::get<DenseVolume<Rgba8>>(*output.values), *parse_view(r.view),
                                            {{"voxd:job", job.id}}));
        break;
      }
      std::shared_ptr<const DenseVolume<float>> map;
      if (r.colour == "thickness") map = job_thickness_map(volume, artifacts, control);
      bytes = to_bytes(preview_png(volume, *parse_view(r.view), map.get(), {{"voxd:job", job.id}}));
      break;
    }
    case AnalysisKind::thickness: bytes = thickness_volume(r, volume, artifacts, control); break;
  }
  artifacts.save(key, bytes);
  return {std::move(bytes), false};
}

nlohmann::json analyses_status(const std::vector<AnalysisRequest>& requests, const char* state) {
  json out = json::array();
  for (const AnalysisRequest& r : requests)
    out.push_back({{"request", api::to_json(r)}, {"state", state}, {"error", nullptr}});
  return out;
}


JobOutput analysis_output(const AnalysisRequest& r, const JobSnapshot& job, const JobStore& store) {
  JobOutput output;
  if (job.streamed && streams_over_slabs(r, *job.job)) {
    output.rle = store.volume_rle(job.id);
    if (job.has_value_volume()) output.values_rle = store.layer_rle(job.id, "values");
    return output;
  }
  output.solid = store.load_volume(job.id);
  if (job.has_value_volume()) output.values = store.load_layer(job.id, "values");
  return output;
}

}  // namespace voxd::server
