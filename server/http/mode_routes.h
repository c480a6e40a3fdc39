#pragma once
// What a job's mode serves beyond its volume (api/job_mode.h), with no mode
// named here:
//  - GET /v1/jobs/{id}/<document>: each JSON document a mode describes its
//    result with (api::JobMode::documents());
//  - GET /v1/jobs/{id}/layers/{k}: one z layer of a colour volume as an RGBA
//    PNG (the PNG stack by separate URLs; format=png-stack is the zip);
// and, for the /volume route, the volume a ?layer= names and the formats a
// mode writes itself.
#include <memory>
#include <string>
#include <vector>

#include "api/job_mode.h"
#include "server/jobs/job_manager.h"

namespace voxd::server {

// The volumes of a succeeded job by name ("values" and its mode's layers);
// a 404 problem when they are gone (the job expired or was deleted meanwhile).
api::VolumeSource volumes_of(JobManager& jobs, const JobSnapshot& job);

// The volume a job's ?layer= names; a 400 problem for a layer its mode does
// not have.
std::shared_ptr<const ValueVolume> job_layer(JobManager& jobs, const JobSnapshot& job, const std::string& layer);

}  // namespace voxd::server
