#pragma once
// Result routes of the manufacturing analysis under /v1/jobs/{id}/…:
// analysis (JSON), radiography (PNG or JSON), section and preview (PNG),
// thickness (the local-thickness volume). Each is computed on first request
// from the job's stored volume, unless the worker prepared it already (the
// job JSON's "analyses"), and kept beside it (server/jobs/job_analyses.h).
namespace voxd::server {

class RouteTable;
class JobManager;

void install_analysis_routes(RouteTable& routes, JobManager& jobs);

}  // namespace voxd::server
