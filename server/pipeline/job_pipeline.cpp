#include "server/pipeline/job_pipeline.h"

#include "voxd/analysis/mass_properties.h"

#include <algorithm>
#include <chrono>
#include <string>

#include <glm/geometric.hpp>

#include "voxd/error.h"
#include "voxd/edge_topology.h"
#include "voxd/mesh_orientation.h"
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

}  // namespace

double StageTimings::total() const {
  double t = 0;
  for (const auto& [name, s] : stages) t += s;
  return t;
}

std::uint64_t estimate_job_memory(const Grid& grid, const api::JobParams& params) {
  return params.mode->memory_estimate(grid, params);
}

std::uint64_t estimate_streamed_job_memory(const Grid& grid, std::int64_t slab_layers, std::uint64_t triangles,
                                           std::uint64_t layer_bytes) {
  const std::uint64_t layer = layer_bytes > 0 ? layer_bytes : bit_volume_bytes({grid.dims.x, grid.dims.y, 1});
  return layer * static_cast<std::uint64_t>(slab_layers + 1) + 64 * triangles + (std::uint64_t{16} << 20);
}

std::int64_t streamed_job_slab_layers(const Grid& grid, const api::JobParams& params, std::uint64_t slab_bytes) {
  const std::uint64_t per_layer = std::max<std::uint64_t>(params.mode->streamed_layer_bytes(grid, params), 1);
  return std::clamp<std::int64_t>(static_cast<std::int64_t>(slab_bytes / per_layer), 1, std::max<std::int64_t>(grid.dims.z, 1));
}

std::uint64_t decode_memory_estimate(std::span<const std::uint8_t> mesh_bytes, std::string_view name_hint,
                                     const DecodeLimits& limits) {
  return decode_memory_estimate(mesh_bytes.size(), detect_mesh_format(mesh_bytes, name_hint), limits);
}

std::uint64_t decode_memory_estimate(std::uint64_t n, MeshFormat format, const DecodeLimits& limits) {
  constexpr std::uint64_t kFixed = std::uint64_t{16} << 20;
  switch (format) {
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

std::uint64_t prepared_mesh_memory(const PreparedVoxelJob& job) {
  return mesh_memory(job.mesh) + (job.welded ? mesh_memory(*job.welded) : 0);
}

void check_voxel_limit(const Grid& grid, std::uint64_t max_voxels, std::string_view hint) {
  if (grid.voxel_count() <= max_voxels) return;
  throw Error(ErrorCode::limit_exceeded,
              "the grid has " + std::to_string(grid.voxel_count()) + " voxels (" + std::to_string(grid.dims.x) + " x " +
                  std::to_string(grid.dims.y) + " x " + std::to_string(grid.dims.z) + "), over the limit of " +
                  std::to_string(max_voxels) + "; use a lower resolution or a larger voxel_size" + std::string(hint));
}

ExecutionPlan plan_execution(const api::JobParams& params, const Grid& grid, const JobLimits& limits) {
  const api::JobMode& mode = *params.mode;
  ExecutionPlan plan;
  plan.no_slabs = mode.streaming_refusal(params);
  if (!plan.no_slabs) plan.no_slabs = limits.output.no_slabs;
  if (params.streaming == api::Streaming::on) {
    if (plan.no_slabs) throw Error(ErrorCode::invalid_argument, "\"streaming\": \"on\": " + *plan.no_slabs);
    if (limits.stream_above_bytes == 0)
      throw Error(ErrorCode::invalid_argument, "\"streaming\": \"on\" needs a stored result: submit the job to POST /v1/jobs");
  }
  plan.streamed = params.streaming == api::Streaming::on ||
                  (params.streaming == api::Streaming::automatic && !plan.no_slabs && limits.stream_above_bytes > 0 &&
                   (mode.faster_in_slabs(params) || estimate_job_memory(grid, params) > limits.stream_above_bytes));
  const bool runs =
      limits.output.takes_runs && mode.makes_runs(params) && (plan.streamed || !limits.output.keeps_volume);
  plan.path = runs ? ExecutionPath::runs : plan.streamed ? ExecutionPath::slabs : ExecutionPath::memory;
  return plan;
}

PreparedVoxelJob prepare_voxel_job(std::span<const std::uint8_t> mesh_bytes, std::string_view name_hint,
                                   const api::JobParams& params, const JobLimits& limits) {
  return prepare_voxel_job(detect_mesh_format(mesh_bytes, name_hint), mesh_bytes, name_hint, params, limits);
}

PreparedVoxelJob prepare_voxel_job(MeshFormat detected, std::span<const std::uint8_t> mesh_bytes,
                                   std::string_view name_hint, const api::JobParams& params, const JobLimits& limits) {
  PreparedVoxelJob job;
  job.params = params;
  // The machine's default device, and a GPU asked for where none can run
  // the job refused before any work.
  if (!job.params.device) job.params.device = limits.device;
  if (*job.params.device == ComputeDevice::cuda && job.params.mode->runs_on_gpu())
    if (const std::string& why = cuda_unavailable_reason(); !why.empty()) throw Error(ErrorCode::invalid_argument, why);
  Stopwatch clock;
  job.format = detected;
  job.mesh = decode_detected_mesh(detected, mesh_bytes, name_hint, limits.decode, &job.decode_warnings);
  job.triangles = job.mesh.triangle_count();
  job.timings.add("parse", clock.lap());

  // The file's unit, once: from here on everything is in millimetres.
  if (params.units != api::LengthUnit::mm) {
    const double scale = api::millimetres_per(params.units);
    for (glm::vec3& v : job.mesh.vertices) v = glm::vec3(glm::dvec3(v) * scale);
  }
  // "auto" chooses from the mesh's edges: of the welded mesh when the job
  // welds it anyway (then kept for the kept mesh and the report), else
  // counted in parallel without welding. The winding number reads a
  // triangle's side, so its mesh is turned outward first; so is a closed
  // mesh that is inside out or has flipped triangles (rare), for the report,
  // the kept mesh and the warnings. A closed, outward mesh pays only the
  // edge count.
  std::optional<EdgeTopology> topology;
  if (api::needs_topology(params)) {
    if (limits.welds_mesh) {
      job.welded = std::make_shared<const Mesh>(weld_vertices(job.mesh));
      topology = job.welded_topology = edge_topology_of_welded(*job.welded);
    } else {
      topology = count_edge_topology(job.mesh);
    }
    job.timings.add("topology", clock.lap());
  }
  job.inside = api::choose_inside_test(params, topology ? &*topology : nullptr);
  job.params.inside = job.inside.test;
  const bool reads_sides = params.mode->uses_inside_test() && job.inside.test == InsideTest::winding;
  const bool suspect = topology && (topology->inconsistent_edges > 0 || topology->six_volume < 0.0);
  if (reads_sides || suspect) {
    job.orientation = orient_outward(job.mesh);
    if (job.orientation->flipped_triangles > 0) {  // the kept mesh and the report are of the mesh as oriented
      job.welded.reset();
      job.welded_topology.reset();
    }
    job.timings.add("orient", clock.lap());
  }
  const api::JobParams& resolved = job.params;

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
  const Aabb part = box;

  // Anisotropic voxels: the engine works where they are cubes.
  if (const glm::dvec3 aspect = params.mode->voxel_aspect(params); aspect != glm::dvec3(1.0)) {
    box.min /= aspect;
    box.max /= aspect;
  }
  job.grid = resolve_grid(params.grid, box);
  // The winding number needs the whole grid: where "auto" chose it for a
  // job that must stream (asked to, or past what memory takes), parity
  // does the job, with a warning.
  std::optional<api::JobWarning> fallback;
  if (job.inside.automatic && job.inside.test == InsideTest::winding) {
    const bool must_stream =
        params.streaming == api::Streaming::on ||
        (!plan_execution(resolved, job.grid, limits).streamed && job.grid.voxel_count() > limits.max_voxels);
    job.params.inside = InsideTest::parity;
    if (must_stream && !plan_execution(resolved, job.grid, limits).no_slabs) {
      job.inside.test = InsideTest::parity;
      job.inside.reason += "; but the winding number needs the whole grid in memory, which this job cannot have, "
                           "so parity, which goes slab by slab";
      fallback = api::JobWarning{"winding-fallback",
                                 "the mesh is not closed, but this job goes slab by slab and the winding number needs the "
                                 "whole grid in memory, so parity was used: expect streaks through the mesh's holes; "
                                 "close the mesh, or use a coarser grid that fits in memory",
                                 {{"voxels", job.grid.voxel_count()}, {"max_voxels_in_memory", limits.max_voxels}}};
    } else {
      job.params.inside = InsideTest::winding;
    }
  }
  // In memory, slab by slab or as runs: asked for, or from the memory it
  // would take.
  const ExecutionPlan plan = plan_execution(resolved, job.grid, limits);
  job.streamed = plan.streamed;
  job.path = plan.path;
  if (job.streamed) {
    check_voxel_limit(job.grid, limits.max_streamed_voxels, "");
    job.slab_layers = streamed_job_slab_layers(job.grid, resolved, limits.stream_slab_bytes);
    job.memory_estimate = estimate_streamed_job_memory(job.grid, job.slab_layers, job.triangles,
                                                       params.mode->streamed_layer_bytes(job.grid, resolved));
  } else {
    const bool could_stream = !plan.no_slabs && limits.stream_above_bytes > 0 && params.streaming == api::Streaming::off;
    check_voxel_limit(job.grid, limits.max_voxels,
                      could_stream ? " (or \"streaming\": \"auto\": slab by slab it needs the memory of one slab, not the grid's)" : "");
    job.memory_estimate = estimate_job_memory(job.grid, resolved);
  }
  job.warnings = api::prepared_job_warnings(resolved, job.inside, job.orientation ? &*job.orientation : nullptr, part,
                                            job.grid);
  if (fallback) job.warnings.push_back(std::move(*fallback));
  job.timings.add("grid", clock.lap());
  return job;
}

namespace {

// What every run does before the voxels: the result's bookkeeping, the mesh
// report of the mesh as uploaded, the rotation, the mode's voxel aspect, the
// exact mass properties in the voxels' frame.
VoxelJobResult begin_voxel_job(PreparedVoxelJob& job, bool with_report, JobControl* control, Stopwatch& clock) {
  VoxelJobResult result;
  result.format = job.format;
  result.triangles = job.triangles;
  result.rotation = job.rotation;
  result.grid = job.grid;
  result.timings = std::move(job.timings);
  result.inside = job.inside;
  result.warnings = job.warnings;
  if (control) control->check_cancelled();
  if (with_report) {
    if (control) control->set_stage("mesh report");
    result.report = job.welded ? mesh_report_of_welded(*job.welded, job.welded_topology ? &*job.welded_topology : nullptr)
                               : make_mesh_report(job.mesh);
    job.welded.reset();
    job.welded_topology.reset();
    result.report->warnings = job.decode_warnings;
    result.report->orientation = job.orientation;
    // Parity asked for by name is not oriented, so only the report sees whether it leaks.
    if (!job.orientation)
      if (auto w = api::leaky_inside_warning(job.inside, result.report->boundary_edges, result.report->nonmanifold_edges))
        result.warnings.push_back(std::move(*w));
    result.timings.add("report", clock.lap());
  }
  if (job.rotation != glm::dmat3(1.0)) {
    rotate_mesh(job.mesh, job.rotation);
    result.timings.add("transform", clock.lap());
  }
  const api::JobMode& mode = *job.params.mode;
  if (const glm::dvec3 aspect = mode.voxel_aspect(job.params); aspect != glm::dvec3(1.0)) {
    const glm::vec3 inverse(1.0 / aspect);
    for (glm::vec3& v : job.mesh.vertices) v *= inverse;
  }
  // Exact mass properties in the frame the voxels are in, for the analysis's
  // side-by-side comparison (cheap: one pass over the triangles).
  if (with_report) result.mesh_mass = mesh_mass_properties(job.mesh);
  return result;
}

// The warning a whole job's empty solid gets: its mesh's area from the
// report, or summed here (only ever for an empty result).
void warn_if_empty(VoxelJobResult& result, const PreparedVoxelJob& job) {
  if (result.filled > 0) return;
  double area = 0.0;
  if (result.report) {
    area = result.report->surface_area;
  } else {
    for (std::size_t t = 0; t < job.mesh.triangles.size(); ++t) {
      const glm::dvec3 a(job.mesh.corner(t, 0)), b(job.mesh.corner(t, 1)), c(job.mesh.corner(t, 2));
      area += glm::length(glm::cross(b - a, c - a)) / 2.0;
    }
  }
  if (auto w = api::empty_result_warning(job.params, result.inside, result.filled, area)) result.warnings.push_back(std::move(*w));
}

}  // namespace

VoxelJobResult execute_voxel_job(PreparedVoxelJob job, bool with_report, JobControl* control, int threads) {
  Stopwatch clock;
  VoxelJobResult result = begin_voxel_job(job, with_report, control, clock);
  const api::JobMode& mode = *job.params.mode;
  // A mode that makes values takes most of the time with them: a parity
  // solid of its own gets the first tenth of the progress bar, the values
  // the rest.
  const double begin = control ? control->span_begin() : 0.0, end = control ? control->span_end() : 1.0;
  auto span = [control](double b, double e) {
    if (control) control->set_span(b, e);
  };
  const bool parity_solid = mode.needs_parity_solid(job.params);
  std::shared_ptr<const BitVolume> parity;
  if (control) control->set_stage("voxelize");
  if (parity_solid) {
    span(begin, begin + 0.1 * (end - begin));
    VoxelizeOptions options;
    options.inside = InsideTest::parity;
    options.threads = threads;
    parity = std::make_shared<const BitVolume>(voxelize(job.mesh, job.grid, options, control));
    result.timings.add("voxelize", clock.lap());
    span(begin + 0.1 * (end - begin), end);
    if (control) control->set_stage(std::string(mode.stage_name()));
  }
  result.volumes = mode.run({job.mesh, job.grid, job.params, threads, control, parity.get()});
  span(begin, end);
  result.timings.add(std::string(mode.stage_name()), clock.lap());
  api::JobVolumes& made = result.volumes;
  if (!made.solid) made.solid = parity ? std::move(parity) : std::make_shared<const BitVolume>();
  if (made.values) made.values_info["type"] = value_type_name(*made.values);
  result.filled = made.solid->count();
  result.timings.add("count", clock.lap());
  warn_if_empty(result, job);
  return result;
}

VoxelJobResult execute_streamed_voxel_job(PreparedVoxelJob job, bool with_report, JobControl* control, int threads,
                                          std::int64_t slab_layers, const BitSlabConsumer& consume,
                                          const ValueSlabConsumer& values) {
  const api::JobMode& mode = *job.params.mode;
  if (auto refusal = mode.streaming_refusal(job.params)) throw Error(ErrorCode::invalid_argument, *refusal);
  if (job.params.has_values() && !values) throw std::logic_error("a streamed job of values without a consumer for them");
  Stopwatch clock;
  VoxelJobResult result = begin_voxel_job(job, with_report, control, clock);
  result.streamed = true;
  const BitSlabConsumer bits = [&](std::int64_t k0, const BitVolume& slab) {
    result.filled += slab.count();
    consume(k0, slab);
  };
  // As in memory: a mode of values whose bits are the parity solid gets it
  // made first, in a tenth of the progress bar.
  const double begin = control ? control->span_begin() : 0.0, end = control ? control->span_end() : 1.0;
  const bool parity_solid = mode.needs_parity_solid(job.params);
  if (control) control->set_stage("voxelize");
  if (parity_solid) {
    if (control) control->set_span(begin, begin + 0.1 * (end - begin));
    VoxelizeOptions options;
    options.inside = InsideTest::parity;
    options.threads = threads;
    voxelize_streamed(job.mesh, job.grid, options, slab_layers, bits, control);
    result.timings.add("voxelize+write", clock.lap());
    if (control) control->set_span(begin + 0.1 * (end - begin), end);
    if (control) control->set_stage(std::string(mode.stage_name()));
  }
  result.volumes.values_info = mode.run_streamed({job.mesh, job.grid, job.params, threads, control, nullptr}, slab_layers,
                                         parity_solid ? BitSlabConsumer([](std::int64_t, const BitVolume&) {}) : bits,
                                         values);
  if (control) control->set_span(begin, end);
  if (auto type = job.params.value_type()) result.volumes.values_info["type"] = value_type_name(*type);
  result.timings.add(parity_solid ? std::string(mode.stage_name()) + "+write" : "voxelize+write", clock.lap());
  warn_if_empty(result, job);
  return result;
}

namespace {

VoxelJobResult execute_runs(PreparedVoxelJob& job, bool with_report, LayerRange range, JobControl* control,
                            int threads, const RunSlabConsumer& consume, const RunSlabPreparer& prepare) {
  const api::JobMode& mode = *job.params.mode;
  if (!mode.makes_runs(job.params))
    throw Error(ErrorCode::invalid_argument, "mode " + std::string(mode.name()) + " with the " +
                                                 to_string(job.params.inside) + " inside test does not make runs");
  Stopwatch clock;
  VoxelJobResult result = begin_voxel_job(job, with_report, control, clock);
  result.streamed = job.streamed;
  if (control) control->set_stage("voxelize");
  api::ModeInput in{job.mesh, job.grid, job.params, threads, control, nullptr};
  in.layers = range;
  in.prepare_runs = prepare;
  mode.run_runs(in, [&](std::int64_t k0, const RunSlab& slab) {
    result.filled += slab.count();
    consume(k0, slab);
  });
  result.timings.add("voxelize+write", clock.lap());
  return result;
}

}  // namespace

VoxelJobResult execute_voxel_runs_job(PreparedVoxelJob job, bool with_report, JobControl* control, int threads,
                                      const RunSlabConsumer& consume, const RunSlabPreparer& prepare) {
  VoxelJobResult result = execute_runs(job, with_report, {}, control, threads, consume, prepare);
  warn_if_empty(result, job);
  return result;
}

VoxelJobResult execute_voxel_layers(PreparedVoxelJob job, LayerRange range, JobControl* control, int threads,
                                    const RunSlabConsumer& consume, const RunSlabPreparer& prepare) {
  VoxelJobResult result = execute_runs(job, /*with_report=*/false, range, control, threads, consume, prepare);
  result.streamed = true;
  return result;
}

VoxelJobResult describe_voxel_job(PreparedVoxelJob job) {
  Stopwatch clock;
  VoxelJobResult result = begin_voxel_job(job, /*with_report=*/true, nullptr, clock);
  result.streamed = true;
  return result;
}

VoxelJobResult run_voxel_job(std::span<const std::uint8_t> mesh_bytes, std::string_view name_hint,
                             const api::JobParams& params, const JobLimits& limits, bool with_report,
                             JobControl* control, int threads) {
  return execute_voxel_job(prepare_voxel_job(mesh_bytes, name_hint, params, limits), with_report, control, threads);
}

}  // namespace voxd
