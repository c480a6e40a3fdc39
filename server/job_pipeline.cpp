#include "server/job_pipeline.h"

#include "voxd/analysis/mass_properties.h"

#include <algorithm>
#include <chrono>
#include <string>

#include "voxd/voxelize/coverage.h"
#include "voxd/error.h"
#include "voxd/voxelize/palette.h"
#include "voxd/encode/palette_export.h"
#include "voxd/voxelize/palette_render.h"
#include "voxd/voxelize/sdf.h"
#include "voxd/voxelize/slice_functions.h"
#include "voxd/transform.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd {
namespace {

class Stopwatch {
 public:
  double lap() {
    const auto now = std::chrono::steady_clock::now();
    const double s = std::chrono::duration<double>(now - last_).count();
    last_ = now;
    return s;
  }

 private:
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

void run_coverage(PreparedVoxelJob& job, int threads, JobControl* control, VoxelJobResult& result) {
  const api::CoverageParams& c = *job.params.coverage;
  CoverageOptions o = c.options;
  o.threads = threads;
  DenseVolume<float> coverage = voxelize_coverage(job.mesh, job.grid, o, control);
  result.values_info = {{"quantity", "coverage"},
                        {"sampling", to_string(o.sampling)},
                        {"covered_volume", covered_voxels(coverage, threads) * job.grid.voxel_volume()}};
  if (c.threshold) {
    result.volume = coverage_threshold(coverage, *c.threshold);
    result.values_info["threshold"] = *c.threshold;
  } else if (c.float_values) {
    result.values = std::move(coverage);
    result.values_info["unit"] = "fraction of the voxel";
  } else {
    result.values = coverage_bytes(coverage, threads);
    result.values_info["unit"] = "fraction of the voxel x 255";
  }
}

void run_sdf(PreparedVoxelJob& job, int threads, JobControl* control, VoxelJobResult& result) {
  SdfOptions o = *job.params.sdf;
  o.threads = threads;
  DenseVolume<float> sdf = signed_distance_field(job.mesh, job.grid, o, control, &result.volume);
  const auto [lo, hi] = std::minmax_element(sdf.values().begin(), sdf.values().end());
  result.values_info = {{"quantity", "signed distance"},
                        {"unit", o.model_units ? "model units" : "voxels"},
                        {"sign_convention", o.sign == SignConvention::inside_negative ? "inside_negative" : "inside_positive"},
                        {"band", o.full ? nlohmann::json("full") : nlohmann::json(o.band)},
                        {"min", *lo},
                        {"max", *hi}};
  result.values = std::move(sdf);
}

void run_palette(PreparedVoxelJob& job, int threads, JobControl* control, VoxelJobResult& result) {
  const api::PaletteParams& p = *job.params.palette;
  PaletteOptions o = p.options;
  o.threads = threads;
  PaletteVolume v = voxelize_palette(job.mesh, job.grid, o, control);
  const glm::dvec3 a = p.voxel_aspect;
  result.values_info = {{"quantity", "palette element"},
                        {"unit", "element index (GET /v1/jobs/{id}/palette)"},
                        {"palette", p.palette_name},
                        {"elements", o.palette.elements.size()},
                        {"metric", to_string(o.metric)},
                        {"rays", o.rays},
                        {"points", o.points},
                        {"seed", o.seed},
                        {"voxel_aspect", {a.x, a.y, a.z}},
                        {"voxel_edges", {job.grid.voxel_size * a.x, job.grid.voxel_size * a.y, job.grid.voxel_size * a.z}},
                        {"layers", {"element", "similarity"}}};
  if (!p.render.empty()) result.values_info["layers"].push_back("display");
  result.values = std::move(v.element);
  result.similarity = std::move(v.similarity);
}

void run_slice(PreparedVoxelJob& job, int threads, JobControl* control, VoxelJobResult& result) {
  SliceOptions o = *job.params.slice;
  o.threads = threads;
  DenseVolume<Rgba8> colours = voxelize_slice(job.mesh, job.grid, o, control);
  // The solid is exactly the coloured voxels (alpha > 0).
  result.volume = BitVolume(job.grid);
  for (std::int64_t k = 0; k < job.grid.dims.z; ++k)
    for (std::int64_t j = 0; j < job.grid.dims.y; ++j) {
      const Rgba8* row = colours.slab(k) + j * job.grid.dims.x;
      std::uint64_t* bits = result.volume.row(j, k);
      for (std::int64_t i = 0; i < job.grid.dims.x; ++i)
        if (row[i].a > 0) bits[i >> 6] |= std::uint64_t{1} << (i & 63);
    }
  const SliceFrame frame = make_slice_frame(job.mesh, o.axis);
  result.values_info = {{"quantity", "colour"},
                        {"unit", "rgba8"},
                        {"function", to_string(o.function)},
                        {"axis", {frame.w.x, frame.w.y, frame.w.z}}};
  result.values = std::move(colours);
}

}  // namespace

double StageTimings::total() const {
  double t = 0;
  for (const auto& [name, s] : stages) t += s;
  return t;
}

std::uint64_t estimate_job_memory(const Grid& grid, const api::JobParams& params) {
  const std::uint64_t bits = static_cast<std::uint64_t>((grid.dims.x + 63) / 64) * 8 *
                             static_cast<std::uint64_t>(grid.dims.y) * static_cast<std::uint64_t>(grid.dims.z);
  std::uint64_t volumes = 1;
  if (params.mode != VoxelMode::surface && params.inside == InsideTest::vote) volumes = 3;
  if (params.mode == VoxelMode::solid_and_surface) volumes += 1;
  // Coverage and distances are computed as one float per voxel; bytes are
  // made from the floats (both alive for a moment). The distance field holds
  // its own solid for the sign beside the job's.
  const std::uint64_t floats = 4 * grid.voxel_count();
  if (params.coverage) return bits * volumes + floats + (params.coverage->float_values ? 0 : grid.voxel_count());
  if (params.sdf) return bits * (volumes + 1) + floats;
  if (params.palette) return bits * volumes + 2 * grid.voxel_count();  // element and similarity bytes
  if (params.slice) return bits * (volumes + 1) + 4 * grid.voxel_count();
  return bits * volumes;
}

std::uint64_t decode_memory_estimate(std::span<const std::uint8_t> mesh_bytes, std::string_view name_hint,
                                     const DecodeLimits& limits) {
  const std::uint64_t n = mesh_bytes.size();
  constexpr std::uint64_t kFixed = std::uint64_t{16} << 20;
  switch (detect_mesh_format(mesh_bytes, name_hint)) {
    // A binary STL record (50 bytes) becomes at most 48 bytes of mesh.
    case MeshFormat::stl_binary: return 2 * n + kFixed;
    // A binary PLY vertex can be 12 bytes and a face 13: the mesh takes up
    // to about 4 times the file (229 MB for a 60 MB file of 20M vertices).
    case MeshFormat::ply: return 5 * n + kFixed;
    // Text is longer than the numbers it holds.
    case MeshFormat::stl_ascii:
    case MeshFormat::obj: return n + kFixed;
    // libdraco in its own process: its decoder state, and the mesh it hands back.
    case MeshFormat::draco:
      return std::min<std::uint64_t>(draco_child_memory(n), limits.max_triangles * 64) + 64 * n + kFixed;
    case MeshFormat::unknown: break;
  }
  return kFixed;
}

std::uint64_t draco_child_memory(std::uint64_t bytes) { return (std::uint64_t{256} << 20) + 256 * bytes; }

std::uint64_t mesh_memory(const Mesh& mesh) {
  return mesh.vertices.capacity() * sizeof(mesh.vertices[0]) + mesh.triangles.capacity() * sizeof(mesh.triangles[0]);
}

PreparedVoxelJob prepare_voxel_job(std::span<const std::uint8_t> mesh_bytes, std::string_view name_hint,
                                   const api::JobParams& params, const JobLimits& limits) {
  PreparedVoxelJob job;
  job.params = params;
  Stopwatch clock;
  job.format = detect_mesh_format(mesh_bytes, name_hint);
  job.mesh = decode_mesh(mesh_bytes, name_hint, limits.decode);
  job.triangles = job.mesh.triangle_count();
  job.timings.add("parse", clock.lap());

  // Only the rotation and the bounds it gives are needed to size the grid;
  // the vertices are rotated by the worker, after the mesh report.
  if (params.rotation) job.rotation = *params.rotation;
  Aabb box = job.rotation == glm::dmat3(1.0) ? bounds(job.mesh) : rotated_bounds(job.mesh, job.rotation);
  if (params.orient_auto) {
    const glm::dmat3 permutation = auto_orient_rotation(box);
    if (permutation != glm::dmat3(1.0)) {
      job.rotation = permutation * job.rotation;
      box = rotated_bounds(job.mesh, job.rotation);
    }
  }

  // Anisotropic palette voxels: the engine works where they are cubes.
  if (params.palette && params.palette->voxel_aspect != glm::dvec3(1.0)) {
    box.min /= params.palette->voxel_aspect;
    box.max /= params.palette->voxel_aspect;
  }
  job.grid = resolve_grid(params.grid, box);
  if (job.grid.voxel_count() > limits.max_voxels)
    throw Error(ErrorCode::limit_exceeded,
                "the grid has " + std::to_string(job.grid.voxel_count()) + " voxels (" +
                    std::to_string(job.grid.dims.x) + " x " + std::to_string(job.grid.dims.y) + " x " +
                    std::to_string(job.grid.dims.z) + "), over the limit of " + std::to_string(limits.max_voxels) +
                    "; use a lower resolution or a larger voxel_size");
  job.memory_estimate = estimate_job_memory(job.grid, params);
  job.timings.add("grid", clock.lap());
  return job;
}

VoxelJobResult execute_voxel_job(PreparedVoxelJob job, bool with_report, JobControl* control, int threads) {
  VoxelJobResult result;
  result.format = job.format;
  result.triangles = job.triangles;
  result.rotation = job.rotation;
  result.grid = job.grid;
  result.timings = std::move(job.timings);
  Stopwatch clock;
  if (control) control->check_cancelled();
  if (with_report) {
    result.report = make_mesh_report(job.mesh);
    result.timings.add("report", clock.lap());
  }
  if (job.rotation != glm::dmat3(1.0)) {
    rotate_mesh(job.mesh, job.rotation);
    result.timings.add("transform", clock.lap());
  }
  if (job.params.palette && job.params.palette->voxel_aspect != glm::dvec3(1.0)) {
    const glm::vec3 inverse(1.0 / job.params.palette->voxel_aspect);
    for (glm::vec3& v : job.mesh.vertices) v *= inverse;
  }
  // Exact mass properties in the frame the voxels are in, for the analysis's
  // side-by-side comparison (cheap: one pass over the triangles).
  if (with_report) result.mesh_mass = mesh_mass_properties(job.mesh);
  VoxelizeOptions options;
  options.mode = job.params.mode;
  options.inside = job.params.inside;
  options.threads = threads;
  if (!job.params.has_values() && !job.params.coverage) {
    result.volume = voxelize(job.mesh, job.grid, options, control);
    result.timings.add("voxelize", clock.lap());
  } else {
    // The values take most of the time: a solid of its own gets the first
    // tenth of the progress bar, the values the rest.
    const double begin = control ? control->span_begin() : 0.0, end = control ? control->span_end() : 1.0;
    const double split = begin + 0.1 * (end - begin);
    auto span = [control](double b, double e) {
      if (control) control->set_span(b, e);
    };
    // Coverage's and the palette's solid is the parity solid of their
    // crossings (a threshold makes the volume from the values instead); the
    // distance field hands back the solid that signs it, the slice colours
    // carry theirs in alpha.
    const bool own_solid = (job.params.coverage && !job.params.coverage->threshold) || job.params.palette;
    if (own_solid) {
      span(begin, split);
      options.inside = InsideTest::parity;
      result.volume = voxelize(job.mesh, job.grid, options, control);
      result.timings.add("voxelize", clock.lap());
    }
    span(own_solid ? split : begin, end);
    if (job.params.coverage) {
      run_coverage(job, threads, control, result);
    } else if (job.params.sdf) {
      run_sdf(job, threads, control, result);
    } else if (job.params.palette) {
      run_palette(job, threads, control, result);
    } else {
      run_slice(job, threads, control, result);
    }
    result.timings.add(job.params.mode_name(), clock.lap());
    if (result.values) result.values_info["type"] = value_type_name(*result.values);
    span(begin, end);
  }
  result.filled = result.volume.count();
  result.timings.add("count", clock.lap());
  return result;
}

void write_palette_mesh(const api::PaletteParams& params, const DenseVolume<std::uint8_t>& element, VolumeFormat format,
                        ByteSink& sink) {
  // The engine ran where voxels are cubes (coordinates / aspect): the
  // export scales that space, origin included, back to model units.
  if (format == VolumeFormat::stl) return write_palette_stl(params.options.palette, element, params.voxel_aspect, sink);
  if (format == VolumeFormat::glb) return write_palette_glb(params.options.palette, element, params.voxel_aspect, sink);
  throw Error(ErrorCode::invalid_argument, std::string("a palette reconstruction is written as stl or glb, not ") + to_string(format));
}

VoxelJobResult run_voxel_job(std::span<const std::uint8_t> mesh_bytes, std::string_view name_hint,
                             const api::JobParams& params, const JobLimits& limits, bool with_report,
                             JobControl* control, int threads) {
  return execute_voxel_job(prepare_voxel_job(mesh_bytes, name_hint, params, limits), with_report, control, threads);
}

}  // namespace voxd
