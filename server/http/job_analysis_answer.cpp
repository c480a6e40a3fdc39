#include "server/http/job_analysis_answer.h"

#include <string>

#include "api/param_error.h"
#include "server/http/job_lookup.h"
#include "server/http/problem.h"
#include "server/jobs/job_manager.h"

namespace voxd::server {
namespace {

ProblemError invalid_query(const std::string& detail) {
  return ProblemError(make_problem(400, "invalid-query", "Invalid query parameter", detail));
}

// A streamed job's request that streams reads the stored RLE slab by slab;
// every other request reads the volumes whole, and on a streamed job only
// while they fit the per-job memory (else the 422 says what does stream).
JobOutput output_for(JobManager& jobs, const JobSnapshot& job, const api::AnalysisRequest& request) {
  JobOutput output;
  if (job.streamed && streams_over_slabs(request, *job.job)) {
    output.rle = jobs.volume_rle(job.id);
    if (job.has_value_volume()) output.values_rle = jobs.values_rle(job.id);
    if (!output.rle || (job.has_value_volume() && !output.values_rle)) throw unknown_job(job.id);
    return output;
  }
  output.solid = jobs.volume(job.id);
  output.values = jobs.values(job.id);
  if (!output.solid || (job.has_value_volume() && !output.values)) throw unknown_job(job.id);
  return output;
}

}  // namespace

api::AnalysisRequest analysis_request_of(api::AnalysisKind kind, const api::Fields& fields) {
  try {
    return api::parse_analysis_request(kind, fields, "");
  } catch (const api::InvalidParams& e) {
    std::string detail;
    for (const auto& f : e.errors()) detail += (detail.empty() ? "" : "; ") + f.path.substr(1) + " " + f.message;
    throw invalid_query(detail);
  }
}

AnalysisAnswer analyse_succeeded_job(JobManager& jobs, const JobSnapshot& job, const api::AnalysisRequest& request,
                                     std::size_t keep_while_sent_from) {
  // Computing (or even serving a kept result, read whole) takes memory
  // beside the job's volumes: held from the budget meanwhile. A streamed
  // job's volume is loaded only for this request, so it counts too.
  const MemoryBudget::Reservation memory = jobs.reserve_memory(
      analysis_memory_on_job(request, *job.job, job.grid, job.streamed, jobs.max_job_memory(), job.triangles),
      "this analysis");
  const JobOutput output = output_for(jobs, job, request);
  try {
    return job_analysis_answer(request, job, output, artifacts_of(jobs, job.id), keep_while_sent_from);
  } catch (const AnalysisRejected& e) {
    throw invalid_query(e.what());
  }
}

}  // namespace voxd::server
