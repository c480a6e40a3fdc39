#pragma once
// A submission's labels (JobLabels, server/jobs/job.h) checked: its name
// (the uploaded file's when the client gives none), its tags, its callback
// URL (which must be one the service's webhook allow-list names, and needs
// the caller's tenant to have a webhook secret), and its tenant, the
// caller's. Refusals are 422 invalid-params naming the field.
#include "server/http/caller.h"
#include "server/http/submission.h"
#include "server/jobs/job.h"
#include "server/tenants/tenant_directory.h"

namespace voxd::server {

inline constexpr std::size_t kMaxJobNameBytes = 256;
inline constexpr std::size_t kMaxJobTags = 32;

JobLabels job_labels_of(const Submission& s, const Caller& caller, TenantDirectory& tenants);

// GET /v1/jobs?name=…&tag=key:value (repeated): the filter on top of the
// caller's own jobs. Throws a 400 invalid-query for a malformed tag.
JobFilter job_filter_of(const httplib::Request& req, const Caller& caller);

}  // namespace voxd::server
