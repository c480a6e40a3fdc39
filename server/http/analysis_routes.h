#pragma once
// Result routes of the manufacturing analysis under /v1/jobs/{id}/…:
// analysis (JSON), radiography (PNG or JSON), section and preview (PNG),
// thickness (the local-thickness volume). Each is computed on first request
// from the job's stored volume, unless the worker prepared it already (the
// job JSON's "analyses"), and kept beside it (server/jobs/job_analyses.h).
#include <functional>
#include <string>
#include <vector>

namespace httplib {
class Server;
struct Request;
struct Response;
}  // namespace httplib

namespace voxd::server {

class JobManager;

using PlainHandler = std::function<void(const httplib::Request&, httplib::Response&)>;
// Wraps a handler so exceptions become problem+json answers.
using Guard = std::function<std::function<void(const httplib::Request&, httplib::Response&)>(PlainHandler)>;

// Registers the routes; `job_path` is the /v1/jobs/{id} pattern (id in match 1).
// Returns the patterns registered, for the 405 answers of other methods.
std::vector<std::string> install_analysis_routes(httplib::Server& server, JobManager& jobs, const std::string& job_path,
                                                 const Guard& guarded);

}  // namespace voxd::server
