#pragma once
// GET /v1/jobs/{id}/volume?format=stl|ply|glb for a job whose mode does not
// write the format itself (a palette job's stl and glb are its
// reconstruction, written by its mode in api/modes/): a mesh of the result, made
// when asked and streamed (voxd/encode/volume_surface.h, mesh_export.h):
//  - bits (solid, surface, solid+surface): the voxel surface, closed and
//    facing out, enclosing the filled voxels' volume exactly;
//  - an sdf job: its zero level set by surface nets, as the page draws it.
// Anything else (grey levels, colours, palette indices) is refused with 400
// invalid-query before any work; a mesh over the per-job memory with 422
// limit-exceeded, and one that does not fit the memory budget now with 429.
#include <string>

#include <httplib.h>

#include "server/http/volume_request.h"
#include "server/jobs/job.h"

namespace voxd::server {

class JobManager;
class Metrics;

bool is_mesh_format(VolumeFormat format);
// Whether the job's result has a surface to mesh: bits, or distances.
bool offers_surface_mesh(const api::JobParams& params);

void answer_surface_mesh(httplib::Response& res, JobManager& jobs, const JobSnapshot& job, const VolumeRequest& v,
                         const std::string& filename, Metrics& metrics);

}  // namespace voxd::server
