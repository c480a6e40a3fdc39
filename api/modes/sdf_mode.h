#pragma once
// "mode": "sdf": the exact signed distance field (Jones 1996,
// voxd/voxelize/sdf.h), signed by the job's inside test. Options under "sdf".
#include "api/job_mode.h"
#include "voxd/voxelize/sdf.h"

namespace voxd::api {

// The engine's options as the job JSON sets them; their inside test is not
// read: the sign comes from the job's (JobParams::inside), resolved per mesh.
struct SdfParams : ModeOptions, SdfOptions {};

const JobMode& sdf_mode();

}  // namespace voxd::api
