#pragma once
// JobSnapshot <-> JSON: the job's record, as stores keep it. The status body
// the API returns (proto-schemas/job-status.schema.json) is this document
// with the job's links and its failure's HTTP status (server/http/job_status.h).
#include <chrono>
#include <string>

#include <nlohmann/json.hpp>

#include "server/jobs/job.h"

namespace voxd::server {

nlohmann::json record_json(const JobSnapshot& job);
// The record a store keeps: the status JSON plus what only the service
// reads back (the mesh's exact mass properties).
nlohmann::json stored_record(const JobSnapshot& job);
// Throws std::exception on a malformed record.
JobSnapshot job_from_json(const nlohmann::json& record);
// RFC 3339 UTC with milliseconds, e.g. 2026-11-22T23:41:30.123Z.
std::string format_time(std::chrono::system_clock::time_point t);
std::chrono::system_clock::time_point parse_time(const std::string& text);
std::optional<JobState> job_state_from_string(const std::string& name);

}  // namespace voxd::server
