// Admission: a submission checked, decoded and prepared on the submitting
// thread (bad meshes and oversized grids are refused at once), answered
// from an identical earlier job's result when its backend keeps one, else
// handed to its backend to wait for a worker.
#include <spdlog/spdlog.h>

#include "api/param_error.h"
#include "server/jobs/content_hash.h"
#include "server/jobs/job_analyses.h"
#include "server/jobs/job_backend.h"
#include "server/jobs/job_engine.h"
#include "server/jobs/kept_mesh.h"
#include "server/jobs/job_store.h"

namespace voxd::server {

namespace {

// The job's volumes as stored, uncompressed: the bits, its values and the
// layers its mode keeps beside them (RLE is usually far smaller; this is
// the bound a result-size cap is checked against at admission).
std::uint64_t result_volume_bytes(const Grid& grid, const api::JobParams& params) {
  const std::uint64_t voxels = grid.voxel_count();
  std::uint64_t bytes = (voxels + 7) / 8;
  if (const std::optional<ValueVolume> type = params.value_type()) {
    const std::uint64_t value = std::visit([]<typename T>(const DenseVolume<T>&) { return sizeof(T); }, *type);
    bytes += voxels * value * (1 + params.mode->stored_layers().size());
  }
  return bytes;
}

}  // namespace

std::shared_ptr<Job> JobEngine::admit(JobBackend& backend, std::vector<std::uint8_t>& mesh_bytes,
                                      const std::string& name_hint, const JobLabels& labels,
                                      const nlohmann::json& params_json,
                                      JobSnapshot* cached_out, std::uint64_t max_voxels) {
  JobStore* const store = backend.store();
  {
    std::lock_guard lock(mutex);
    if (!accepting) throw NotAccepting("the service is shutting down and accepts no new jobs");
  }
  if (const std::size_t waiting = backend.waiting(); waiting >= config.queue_size)
    throw queue_full(waiting);
  const auto parsed = std::make_shared<const api::JobParams>(api::parse_job_params(params_json));
  const api::JobParams& params = *parsed;
  if (store && store->free_bytes() < config.min_free_disk)
    throw StorageFull("the service's storage has less than " + std::to_string(config.min_free_disk >> 20) +
                      " MiB free and takes no new jobs until results expire or are deleted; retry later");
  // A job that is never stored is never answered from the store: it skips
  // the hash (a tenth of a small job's time).
  // The tenant is part of the identity: one tenant's upload never answers
  // another's (nor tells it that the same part was submitted).
  const std::string hash =
      store ? content_hash(mesh_bytes, labels.tenant.empty() ? params_json.dump() : params_json.dump() + "\ntenant:" + labels.tenant)
            : std::string();

  // An identical earlier submission that succeeded answers this one.
  if (store && cached_out) {
    if (const std::optional<JobSnapshot> original = backend.earlier_success(hash)) {
      JobSnapshot s = *original;
      s.id = new_job_id();
      s.created_at = s.started_at = s.finished_at = format_now();
      s.params = params_json;
      s.job = parsed;
      s.labels = labels;
      s.cached = true;
      s.timings.clear();
      s.analyses = analyses_status(params.analyses, "on_request");
      try {
        store->share_volume(original->id, s.id);
        store->save(s);
        backend.keep_answered(s);
        *cached_out = s;
        return nullptr;
      } catch (const BackendUnavailable&) {
        throw;
      } catch (const std::exception& e) {
        // The original was deleted meanwhile: fall through and compute.
        store->remove(s.id);
        spdlog::info("job cache miss for {}: {}", original->id, e.what());
      }
    }
  }

  if (!store && !params.analyses.empty())
    throw api::InvalidParams(std::vector<api::FieldError>{
        {"/analyses", "synchronous voxelization answers with the volume only; submit to POST /v1/jobs for analyses"}});
  // The upload while it is decoded, then the job's own share: until the
  // decoded mesh is known, a bound from the bytes and the format.
  // The format is detected once, here.
  const MeshFormat format = detect_mesh_format(mesh_bytes, name_hint);
  MemoryBudget::Reservation decoding =
      budget.reserve(decode_memory_estimate(mesh_bytes.size(), format, config.limits.decode), "decoding this upload");
  PreparedVoxelJob prepared = prepare_voxel_job(format, mesh_bytes, name_hint, params, job_limits(store != nullptr));
  if (max_voxels > 0 && prepared.grid.voxel_count() > max_voxels)
    throw Error(ErrorCode::limit_exceeded, "the grid has " + std::to_string(prepared.grid.voxel_count()) +
                                               " voxels; synchronous voxelization takes at most " +
                                               std::to_string(max_voxels) + ": submit it to POST /v1/jobs instead");
  if (prepared.memory_estimate > config.max_job_memory)
    throw Error(ErrorCode::limit_exceeded,
                "the job needs about " + std::to_string(prepared.memory_estimate >> 20) + " MiB for its volumes, over the limit of " +
                    std::to_string(config.max_job_memory >> 20) + " MiB; use a lower resolution or a larger voxel_size");
  if (store && config.max_result_bytes > 0) {
    // The volumes, and the mesh the job keeps beside them (kept_mesh.h).
    const std::uint64_t bytes = result_volume_bytes(prepared.grid, params) + kept_mesh_bytes(prepared.triangles);
    if (bytes > config.max_result_bytes)
      throw Error(ErrorCode::limit_exceeded,
                  "the job's volumes and mesh take up to " + std::to_string(bytes >> 20) + " MiB to store, over the service's cap of " +
                      std::to_string(config.max_result_bytes >> 20) +
                      " MiB a result; use a lower resolution or a larger voxel_size");
  }
  const std::uint64_t memory = prepared_mesh_memory(prepared) + prepared.memory_estimate + analyses_memory(params, prepared);

  auto job = std::make_shared<Job>();
  job->backend = &backend;
  JobSnapshot& s = job->snap;
  s.id = new_job_id();
  s.state = JobState::queued;
  s.created_at = format_now();
  s.params = params_json;
  s.job = parsed;
  s.labels = labels;
  s.mesh_format = to_string(prepared.format);
  s.triangles = prepared.triangles;
  s.grid = prepared.grid;
  s.streamed = prepared.streamed;
  s.execution = prepared.path;
  s.timings = prepared.timings.stages;
  s.inside = prepared.inside;
  s.warnings = prepared.warnings;
  s.content_hash = hash;
  s.analyses = analyses_status(params.analyses, "pending");
  backend.accept(JobBackend::Admitted{job, std::move(prepared), mesh_bytes, name_hint, decoding, memory});
  return job;
}

void JobEngine::enqueue_local(JobBackend::Admitted& admitted, JobStore* store) {
  Job& job = *admitted.job;
  admitted.mesh_bytes.clear();
  admitted.mesh_bytes.shrink_to_fit();
  admitted.decoding.release();
  job.memory = budget.reserve(admitted.memory, "the job");
  job.prepared = std::move(admitted.prepared);
  const JobSnapshot& s = job.snap;
  // Recorded before a worker can see it, so the final record always wins. A
  // job that cannot be recorded is not accepted (a full disk is a 507).
  if (store) store->save(s);
  {
    std::lock_guard lock(mutex);
    // Queued under the table's lock: a worker that takes it at once finds it.
    const bool closing = !accepting;
    if (closing || !local_queue->submit(s.id)) {
      const QueueFull full = queue_full(local_queue->depth());
      if (store) store->remove(s.id);
      if (closing) throw NotAccepting("the service is shutting down and accepts no new jobs");
      throw full;
    }
    jobs.emplace(s.id, admitted.job);
    announce(s);
  }
  deliver();
}

}  // namespace voxd::server
