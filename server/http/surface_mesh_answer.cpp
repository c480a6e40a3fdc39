#include "server/http/surface_mesh_answer.h"

#include <memory>
#include <stdexcept>

#include "server/http/job_lookup.h"
#include "server/http/problem.h"
#include "server/http/volume_stream.h"
#include "server/jobs/job_manager.h"
#include "server/jobs/memory_budget.h"
#include "voxd/analysis/sdf_render.h"
#include "voxd/encode/mesh_export.h"
#include "voxd/encode/volume_surface.h"
#include "voxd/error.h"

namespace voxd::server {
namespace {

// What a mesh takes while it is made, a face or a quad: its keys, corner
// nodes and vertex ids, two triangles and about two vertices (voxel
// surface); less for surface nets, held to the same.
constexpr std::uint64_t kBytesPerFace = 128;

// The memory a mesh takes while it is made and sent, held from the service's
// budget as the analyses' is (429 when it is taken now). A mesh over the
// per-job memory is refused outright.
std::shared_ptr<MemoryBudget::Reservation> hold_memory(std::uint64_t faces, std::uint64_t volume_bytes, JobManager& jobs,
                                                       const char* what) {
  const std::uint64_t bytes = faces * kBytesPerFace + volume_bytes;
  if (bytes > jobs.max_job_memory())
    throw Error(ErrorCode::limit_exceeded,
                std::string(what) + " of this job has " + std::to_string(faces) + " faces and would take about " +
                    std::to_string(bytes >> 20) + " MiB to make, over the per-job memory of " +
                    std::to_string(jobs.max_job_memory() >> 20) +
                    " MiB: ask for the volume (format rle or nrrd) and mesh it where there is room");
  return std::make_shared<MemoryBudget::Reservation>(jobs.reserve_memory(bytes, what));
}

// Sample edges whose ends differ in sign: the quads surface nets makes.
std::uint64_t sign_changes(const DenseVolume<float>& d) {
  const glm::i64vec3 n = d.grid().dims;
  std::uint64_t quads = 0;
  for (std::int64_t k = 0; k < n.z; ++k)
    for (std::int64_t j = 0; j < n.y; ++j)
      for (std::int64_t i = 0; i < n.x; ++i) {
        const bool in = d.at(i, j, k) < 0;
        quads += (i + 1 == n.x || (d.at(i + 1, j, k) < 0) != in) + (j + 1 == n.y || (d.at(i, j + 1, k) < 0) != in) +
                 (k + 1 == n.z || (d.at(i, j, k + 1) < 0) != in);
      }
  return quads;
}

void write_mesh(VolumeFormat format, const Mesh& mesh, const std::string& description, ByteSink& sink) {
  if (format == VolumeFormat::stl) return write_mesh_stl(mesh, description, sink);
  if (format == VolumeFormat::ply) return write_mesh_ply(mesh, description, sink);
  write_mesh_glb(mesh, description, sink);
}

}  // namespace

bool is_mesh_format(VolumeFormat format) {
  return format == VolumeFormat::stl || format == VolumeFormat::ply || format == VolumeFormat::glb;
}

bool offers_surface_mesh(const api::JobParams& params) {
  return !params.has_values() || params.mode->distance_values();
}

void answer_surface_mesh(httplib::Response& res, JobManager& jobs, const JobSnapshot& job, const VolumeRequest& v,
                         const std::string& filename, Metrics& metrics) {
  const api::JobParams& params = *job.job;
  const std::string format = to_string(v.format);
  std::shared_ptr<const Mesh> mesh;
  std::shared_ptr<MemoryBudget::Reservation> memory;  // until the mesh is sent
  std::string description;
  if (!job.has_value_volume()) {
    if (job.streamed && bit_volume_bytes(job.grid.dims) > jobs.max_job_memory())
      throw Error(ErrorCode::limit_exceeded,
                  "this job's volume was made slab by slab and, at " + std::to_string(bit_volume_bytes(job.grid.dims) >> 20) +
                      " MiB, is over the per-job memory of " + std::to_string(jobs.max_job_memory() >> 20) +
                      " MiB, so its voxel surface cannot be made here: ask for format rle or nrrd, which stream");
    const auto volume = jobs.volume(job.id);
    if (!volume) throw unknown_job(job.id);
    memory = hold_memory(boundary_face_count(*volume), 0, jobs, "the voxel surface");
    mesh = std::make_shared<const Mesh>(voxel_surface(*volume));
    description = "voxel surface, model units";
  } else {
    const ValueVolume type = *params.value_type();
    if (!params.mode->distance_values())
      throw ProblemError(make_problem(
          400, "invalid-query", "Invalid query parameter",
          format + " is a mesh of the result: the voxel surface of a solid, surface or solid+surface job, or the zero "
                   "level set of an sdf job; a " + std::string(params.mode->name()) + " job holds " +
                   value_type_name(type) + " values, which have no surface to mesh: ask for rle, raw or nrrd"));
    const std::uint64_t bytes = job.grid.voxel_count() * 4;
    if (bytes > jobs.max_job_memory())
      throw Error(ErrorCode::limit_exceeded, "this job's distances take " + std::to_string(bytes >> 20) +
                                                 " MiB, over the per-job memory of " +
                                                 std::to_string(jobs.max_job_memory() >> 20) +
                                                 " MiB, so their zero level set cannot be made here: ask for format "
                                                 "rle or nrrd, which stream");
    const auto values = jobs.values(job.id);
    if (!values) throw unknown_job(job.id);
    const auto field = params.mode->distance_field(params, *values);
    if (!field || !field->sdf) throw std::logic_error("the sdf job's values are not a distance field");
    memory = hold_memory(sign_changes(*field->sdf), bytes, jobs, "the zero level set");
    // Half a voxel beyond the grid is outside, in the values' unit (the page's rule).
    mesh = std::make_shared<const Mesh>(
        zero_level_set(*field->sdf, field->inside_negative, static_cast<float>(0.5 * field->units_per_voxel)));
    description = "zero level set (surface nets), model units";
  }
  res.set_header("X-Voxd-Mesh-Triangles", std::to_string(mesh->triangles.size()));
  stream_encoded(
      res, media_type(v.format),
      [mesh, memory, description, format = v.format](ByteSink& sink) { write_mesh(format, *mesh, description, sink); },
      v.gzip,
      filename, &metrics);
}

}  // namespace voxd::server
