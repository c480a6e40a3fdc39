#pragma once
// One analysis of a succeeded job, as the analysis routes and the job's
// report (report_route.cpp) make it: the memory it needs held from the
// budget meanwhile, the job's volumes read (a streamed job's slab by slab
// where the analysis streams), the kept result when there is one. A request
// the analysis cannot take is a 400 invalid-query.
#include <cstdint>

#include "api/analysis_request.h"
#include "server/jobs/job.h"
#include "server/jobs/job_analyses.h"

namespace voxd::server {

class JobManager;

// The analysis request of a query's fields; every problem in them goes into
// one 400 invalid-query answer.
api::AnalysisRequest analysis_request_of(api::AnalysisKind kind, const api::Fields& fields);

// `keep_while_sent_from`: see job_analysis_answer (job_analyses.h).
AnalysisAnswer analyse_succeeded_job(JobManager& jobs, const JobSnapshot& job, const api::AnalysisRequest& request,
                                     std::size_t keep_while_sent_from = SIZE_MAX);

}  // namespace voxd::server
