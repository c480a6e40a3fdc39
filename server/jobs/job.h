#pragma once
// A job as the rest of the service sees it: its state, its snapshot, why it
// failed, what it produced, the counts by state, and the two ways a
// submission is refused before it is a job. Everything that keeps, moves or
// shows jobs includes this (the store, the shared records, the events, the
// analyses, the routes), not the engine that runs them (job_manager.h).
#include <algorithm>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "api/inside_choice.h"
#include "api/job_params.h"
#include "api/job_warning.h"
#include "server/pipeline/job_pipeline.h"
#include "server/jobs/stored_blob.h"
#include "voxd/analysis/mass_properties.h"
#include "voxd/bit_volume.h"
#include "voxd/enum_names.h"

namespace voxd::server {

enum class JobState { queued, running, succeeded, failed, cancelled };
inline constexpr EnumNames<JobState, 5> kJobStateNames{{
    {JobState::queued, "queued"}, {JobState::running, "running"}, {JobState::succeeded, "succeeded"},
    {JobState::failed, "failed"}, {JobState::cancelled, "cancelled"}}};
inline const char* to_string(JobState state) noexcept { return name_of(kJobStateNames, state); }
// Succeeded, failed or cancelled: the state will not change again.
inline bool finished(JobState s) { return s == JobState::succeeded || s == JobState::failed || s == JobState::cancelled; }

// Why a job failed, in the terms of an RFC 9457 problem ("type" is a short
// slug such as "interrupted", "invalid-mesh", "limit-exceeded", "internal").
struct JobFailure {
  std::string type;
  std::string title;
  std::string detail;
};

// A job that failed for a reason of ours, not its input (an exception no
// check foresaw): the details are logged, not shown.
inline JobFailure internal_failure() {
  return JobFailure{"internal", "Internal error", "the job failed unexpectedly; it was logged"};
}

// Who a job belongs to and how its owner knows it, given at submission and
// kept apart from its params: none of it changes what the job makes, so
// none of it is in the params' canonical JSON (the tenant is in the content
// hash, so that one tenant's upload never answers another's).
struct JobLabels {
  // The tenant that submitted it (server/tenants/tenant_directory.h); empty
  // for a service without tenants and for --api-keys holders.
  std::string tenant;
  std::string name;                                  // the client's, else the uploaded file's name
  std::vector<std::pair<std::string, std::string>> tags;  // sorted by key, keys unique
  std::string callback;                              // URL notified when the job ends (webhooks)
};

// A consistent copy of one job, safe to use after the job table changes.
struct JobSnapshot {
  std::string id;  // 32 lowercase hex characters, random
  JobLabels labels;
  JobState state = JobState::queued;
  double progress = 0.0;  // 0..1, never going back while the job runs
  // What a running job is doing now ("mesh report", "voxelize" or the mode's
  // stage, "store", "analysis: radiography"); empty otherwise.
  std::string stage;
  std::string created_at, started_at, finished_at;  // RFC 3339 UTC, empty until reached
  nlohmann::json params;                            // the job JSON as submitted
  // The job JSON parsed, once, when the job is accepted or its record read:
  // its mode (params->mode) says what the job makes and serves.
  std::shared_ptr<const api::JobParams> job;
  std::string mesh_format;
  std::uint64_t triangles = 0;
  std::optional<MeshReport> mesh;  // set once the worker made it
  std::optional<MassProperties> mesh_mass;  // exact, voxel frame; kept in the record, not in the status JSON
  Grid grid;                       // resolved at submission
  std::vector<std::pair<std::string, double>> timings;  // stage -> seconds
  std::optional<std::uint64_t> filled_voxels;           // when succeeded
  // The inside test and why (api/inside_choice.h), set when the job is
  // prepared: "auto" chooses it from the mesh.
  std::optional<api::InsideChoice> inside;
  // What the user should know about the result (api/job_warning.h): from
  // preparing the job, then from running it.
  std::vector<api::JobWarning> warnings;
  std::optional<JobFailure> failure;                    // when failed
  std::string content_hash;  // SHA-256 of mesh bytes + canonical params JSON + tenant (hex)
  // Bytes its result takes in the store once succeeded (volume, layers,
  // kept mesh and analyses made by its worker): what a tenant's stored-bytes
  // quota counts.
  std::uint64_t stored_bytes = 0;
  bool cached = false;       // answered from an identical earlier job's result
  // The volume was made slab by slab and is kept only as its stored RLE:
  // it is re-encoded and analysed slab by slab, never loaded whole past
  // the per-job memory.
  bool streamed = false;
  // How it runs (plan_execution, server/pipeline/job_pipeline.h): the path a CLI run
  // of the same params takes too.
  ExecutionPath execution = ExecutionPath::memory;
  // The job JSON's "analyses", one entry each: {"request", "url", "state",
  // "error"}; state pending -> ready | failed, or on_request for a job
  // answered from an earlier one's result (computed when first asked).
  nlohmann::json analyses = nlohmann::json::array();
  // A value job's values once succeeded: {"type": "u8"|"f32"|"rgba8",
  // "quantity", "unit", ...} (VoxelJobResult::values_info); null otherwise.
  // A mode that makes bits from its values (a threshold) gives no "type".
  nlohmann::json values = nullptr;
  // Whether the job's result is a volume of values rather than bits.
  bool has_value_volume() const { return values.is_object() && values.contains("type"); }
};

// What a succeeded job produced: the volumes its mode made (api/job_volumes.h,
// the same type the pipeline hands over, kept as it is), or for a streamed
// job their stored files.
struct JobOutput : api::JobVolumes {
  // A streamed job's volume as stored (solid is then null): what streams is
  // answered by replaying it slab by slab (voxd/encode/rle_slabs.h); and a
  // streamed job's values as stored (values is then null).
  std::shared_ptr<const StoredBlob> rle;
  std::shared_ptr<const StoredBlob> values_rle;
};

// What removing a job did: cancelled one that waited or ran, deleted a
// finished one with its results, or found none.
enum class RemoveResult { cancelled, deleted, not_found };

// Submission refused because the queue is full: HTTP 429 with Retry-After.
class QueueFull : public std::runtime_error {
 public:
  QueueFull(const std::string& message, int retry_after_seconds)
      : std::runtime_error(message), retry_after_seconds_(retry_after_seconds) {}
  int retry_after_seconds() const { return retry_after_seconds_; }

 private:
  int retry_after_seconds_;
};

// Submission refused because the service is shutting down: HTTP 503.
class NotAccepting : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Embedded: every job the service keeps, by state. Shared: this replica's
// jobs (queued by it and waiting here for nothing: 0; running here; and
// finished by its workers since it started), the shared queue's depth and
// the replicas alive.
// What one tenant holds now, against its quotas (server/tenants/).
struct TenantUsage {
  std::uint64_t queued = 0, running = 0;
  std::uint64_t stored_bytes = 0;  // of its succeeded jobs
};

// Which jobs a listing shows: one tenant's (all when `tenant` is unset),
// with this name, carrying every one of these tags.
struct JobFilter {
  std::optional<std::string> tenant;
  std::string name;  // empty: any
  std::vector<std::pair<std::string, std::string>> tags;
  bool matches(const JobSnapshot& s) const {
    if (tenant && s.labels.tenant != *tenant) return false;
    if (!name.empty() && s.labels.name != name) return false;
    for (const auto& tag : tags)
      if (std::find(s.labels.tags.begin(), s.labels.tags.end(), tag) == s.labels.tags.end()) return false;
    return true;
  }
  // Whether it asks for more than the tenant (the shared index has only that).
  bool by_label() const { return !name.empty() || !tags.empty(); }
};

struct JobCounts {
  std::uint64_t queued = 0, running = 0, succeeded = 0, failed = 0, cancelled = 0;
  std::size_t queue_depth = 0;
  std::optional<std::size_t> live_replicas;  // shared backends only
};

}  // namespace voxd::server
