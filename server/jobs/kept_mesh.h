#pragma once
// The job's own mesh, kept beside its volumes for as long as they are (an
// artifact of the job, shared with an identical submission's answer): what
// the thickness on the part (GET /v1/jobs/{id}/thickness?format=ply|glb|
// json) is painted on. Welded, as uploaded (the user's frame), with the
// rotation the job applied before voxelizing, so it is read in the grid's
// frame and written back in the user's.
#include <cstdint>
#include <memory>
#include <string>

#include <glm/mat3x3.hpp>

#include "voxd/mesh.h"

namespace voxd {
struct PreparedVoxelJob;  // server/pipeline/job_pipeline.h
}

namespace voxd::server {

inline constexpr const char* kKeptMeshKey = "surface-mesh";

struct KeptMesh {
  Mesh mesh;  // welded, as uploaded
  glm::dmat3 rotation{1.0};  // uploaded frame -> the grid's
};

std::string encode_kept_mesh(const Mesh& welded, const glm::dmat3& rotation);
// Throws std::runtime_error when the bytes are not a kept mesh.
KeptMesh decode_kept_mesh(const std::string& bytes);
// At most what a mesh of `triangles` triangles takes kept (none shared), for
// the result's size cap at admission.
std::uint64_t kept_mesh_bytes(std::uint64_t triangles);

class JobStore;
// Keeps the prepared job's mesh (welded) as the job's artifact, and returns
// the welded mesh (its mesh report reads it: PreparedVoxelJob::welded).
// Throws what the store's save_artifact throws.
std::shared_ptr<const Mesh> keep_job_mesh(const JobStore& store, const std::string& id, const PreparedVoxelJob& prepared);

}  // namespace voxd::server
