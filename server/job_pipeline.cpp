#include "server/job_pipeline.h"

#include <chrono>
#include <string>

#include "voxd/error.h"
#include "voxd/transform.h"
#include "voxd/voxelize.h"

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
  const std::uint64_t bits = static_cast<std::uint64_t>((grid.dims.x + 63) / 64) * 8 *
                             static_cast<std::uint64_t>(grid.dims.y) * static_cast<std::uint64_t>(grid.dims.z);
  std::uint64_t volumes = 1;
  if (params.mode != VoxelMode::surface && params.inside == InsideTest::vote) volumes = 3;
  if (params.mode == VoxelMode::solid_and_surface) volumes += 1;
  return bits * volumes;
}

VoxelJobResult run_voxel_job(std::span<const std::uint8_t> mesh_bytes, std::string_view name_hint,
                             const api::JobParams& params, const JobLimits& limits, bool with_report,
                             JobControl* control, int threads) {
  VoxelJobResult result;
  Stopwatch clock;
  result.format = detect_mesh_format(mesh_bytes, name_hint);
  Mesh mesh = decode_mesh(mesh_bytes, name_hint, limits.decode);
  result.triangles = mesh.triangle_count();
  result.timings.add("parse", clock.lap());
  if (control) control->check_cancelled();

  if (with_report) {
    result.report = make_mesh_report(mesh);
    result.timings.add("report", clock.lap());
  }

  bool rotated = false;
  if (params.rotation) {
    rotate_mesh(mesh, *params.rotation);
    result.rotation = *params.rotation;
    rotated = true;
  }
  if (params.orient_auto) {
    const glm::dmat3 permutation = auto_orient_rotation(bounds(mesh));
    if (permutation != glm::dmat3(1.0)) {
      rotate_mesh(mesh, permutation);
      result.rotation = permutation * result.rotation;
      rotated = true;
    }
  }
  if (rotated) result.timings.add("transform", clock.lap());

  result.grid = resolve_grid(params.grid, bounds(mesh));
  if (result.grid.voxel_count() > limits.max_voxels)
    throw Error(ErrorCode::limit_exceeded,
                "the grid has " + std::to_string(result.grid.voxel_count()) + " voxels, over the limit of " +
                    std::to_string(limits.max_voxels) + "; use a lower resolution or a larger voxel_size");
  if (control) control->check_cancelled();

  VoxelizeOptions options;
  options.mode = params.mode;
  options.inside = params.inside;
  options.threads = threads;
  result.volume = voxelize(mesh, result.grid, options, control);
  result.timings.add("voxelize", clock.lap());
  result.filled = result.volume.count();
  result.timings.add("count", clock.lap());
  return result;
}

}  // namespace voxd
