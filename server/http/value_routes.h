#pragma once
// What palette and slice jobs serve beyond their volume:
//  - GET /v1/jobs/{id}/palette: the palette (each element's half-spaces and
//    volume), the metric and sampling, the chosen-element histogram and,
//    with a rendering palette, the display objects and their histogram;
//  - GET /v1/jobs/{id}/layers/{k}: one z layer of a slice job as an RGBA
//    PNG (the PNG stack by separate URLs; format=png-stack is the zip).
// The /volume route's palette forms (layer=similarity|display, format stl
// or glb) are answered by answer_palette_volume.
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "server/http/analysis_routes.h"
#include "server/http/metrics.h"
#include "server/jobs/job_manager.h"
#include "voxd/encode/volume_format.h"

namespace voxd::server {

std::vector<std::string> install_value_routes(httplib::Server& server, JobManager& jobs, const std::string& job_path,
                                              const Guard& guarded);

// The volume a palette job's `layer` names ("element", "similarity" or
// "display"), for the /volume route; throws a 400 problem for an unknown
// layer, a layer of another job, or "display" without a rendering palette.
std::shared_ptr<const ValueVolume> palette_layer(JobManager& jobs, const JobSnapshot& job, const std::string& layer);

}  // namespace voxd::server
