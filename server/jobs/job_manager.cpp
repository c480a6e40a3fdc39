#include "server/jobs/job_manager.h"

#include <algorithm>
#include <condition_variable>
#include <mutex>
#include <random>
#include <thread>
#include <unordered_map>

#include <spdlog/spdlog.h>

#include "api/error_table.h"
#include "api/param_error.h"
#include "server/jobs/content_hash.h"
#include "server/jobs/job_analyses.h"
#include "voxd/encode/slab_writer.h"
#include "server/jobs/expiry.h"
#include "server/jobs/job_record.h"
#include "server/jobs/job_events.h"
#include "server/jobs/job_queue.h"
#include "server/jobs/job_store.h"
#include "server/jobs/local_job_store.h"
#include "server/jobs/volume_cache.h"
#include "server/log_safe.h"
#include "voxd/error.h"
#include "voxd/parallel.h"

namespace voxd::server {

namespace {

using Clock = std::chrono::system_clock;


std::string new_job_id() {
  thread_local std::mt19937_64 rng{std::random_device{}() ^ (static_cast<std::uint64_t>(std::random_device{}()) << 32)};
  static constexpr char kHex[] = "0123456789abcdef";
  std::string id(32, '0');
  for (int half = 0; half < 2; ++half) {
    std::uint64_t r = rng();
    for (int i = 0; i < 16; ++i, r >>= 4) id[static_cast<std::size_t>(half * 16 + i)] = kHex[r & 15];
  }
  return id;
}

JobFailure interrupted(const char* was) {
  return {"interrupted", "Interrupted by a restart",
          std::string("the job was ") + was + " when the service stopped; submit it again"};
}

}  // namespace

struct Job {
  JobSnapshot snap;
  std::optional<PreparedVoxelJob> prepared;  // until a worker takes it
  JobControl control;
  bool ephemeral = false;           // synchronous job: never stored, dropped after use
  JobOutput result;  // a synchronous job's volumes, for its caller
  bool stopped_by_shutdown = false;  // cancelled because the service stops
  // The job's share of the memory budget (its decoded mesh, volumes and
  // analyses), from acceptance until it ends.
  MemoryBudget::Reservation memory;
  // Serializes this job's store writes with its removal: a worker writing the
  // final record just after a client deleted the finished job must not bring
  // it back on disk (and after a restart, in the API).
  std::mutex store_mutex;
  bool removed = false;  // guarded by store_mutex
};

struct JobManager::Impl {
  explicit Impl(JobManagerConfig c)
      : config(std::move(c)),
        store(config.store ? config.store : std::make_shared<LocalJobStore>(config.data_dir)),
        queue(config.queue ? config.queue : std::make_shared<InProcessJobQueue>(config.queue_size)),
        events(config.on_state_change),
        budget(config.memory_budget ? config.memory_budget : available_memory() / 10 * 6) {}

  JobManagerConfig config;
  // The seams a shared backend replaces (server/jobs/job_store.h, job_queue.h).
  std::shared_ptr<JobStore> store;
  std::shared_ptr<JobQueue> queue;
  JobEvents events;
  VolumeCache cache{std::size_t{1} << 30};
  MemoryBudget budget;
  int engine_threads = 0;

  // The job table: every job this process knows, by id.
  mutable std::mutex mutex;
  std::condition_variable finished_cv;  // synchronous callers wait here
  std::unordered_map<std::string, std::shared_ptr<Job>> jobs;
  std::unordered_map<std::string, std::string> succeeded_by_hash;  // content hash -> job id
  bool accepting = true;
  double recent_job_seconds = 1.0;  // moving average, for Retry-After

  std::vector<std::thread> workers;
  std::unique_ptr<ExpiryTimer> expiry;  // sweeps expired jobs until shutdown
  bool shut_down = false;

  void announce(const JobSnapshot& s) { events.announce(s); }  // caller holds mutex: the table's order
  void deliver() { events.deliver(); }                         // caller holds no lock

  void persist(Job& job, const JobSnapshot& s) const {
    if (job.ephemeral) return;
    std::lock_guard guard(job.store_mutex);
    if (job.removed) return;
    try {
      store->save(s);
    } catch (const std::exception& e) {
      spdlog::error("job {}: cannot write its record: {}", s.id, e.what());
    }
  }

  void cache_put(const std::string& id, const JobOutput& output) {
    if (!output.solid) return;  // streamed: kept on disk only
    if (output.values) cache.put(VolumeCache::layer_key(id, "values"), output.values, byte_size(*output.values));
    for (const auto& [name, layer] : output.layers) cache.put(VolumeCache::layer_key(id, name), layer, byte_size(*layer));
    cache.put(id, output.solid, output.solid->byte_size());
  }

  JobSnapshot snapshot_of(const Job& job) const {
    JobSnapshot s = job.snap;
    if (s.state == JobState::running) s.progress = job.control.progress();
    return s;
  }

  // The analyses the job JSON asked for, computed now and kept as the
  // routes would keep them. A request the grid cannot answer fails alone;
  // cancellation stops the job.
  nlohmann::json prepare_analyses(Job& job, const std::vector<api::AnalysisRequest>& requests, const VoxelJobResult& r,
                                  const JobOutput& output) {
    nlohmann::json status = analyses_status(requests, job.snap.id, "pending");
    if (requests.empty()) return status;
    JobSnapshot view;
    {
      std::lock_guard lock(mutex);
      view = job.snap;
    }
    view.mesh = r.report;
    view.mesh_mass = r.mesh_mass;
    view.values = r.values_info;
    const std::string id = view.id;
    const ArtifactAccess artifacts{
        id, [this, id](const std::string& key) { return store->load_artifact(id, key); },
        [this, &job, id](const std::string& key, const std::string& bytes) {
          std::lock_guard guard(job.store_mutex);
          if (job.removed) return;
          try {
            store->save_artifact(id, key, bytes);
          } catch (const std::exception& e) {
            spdlog::warn("job {}: cannot keep artifact {}: {}", id, key, e.what());
          }
        }};
    for (std::size_t i = 0; i < requests.size(); ++i) {
      const double n = static_cast<double>(requests.size());
      job.control.set_span(0.5 + 0.5 * static_cast<double>(i) / n, 0.5 + 0.5 * static_cast<double>(i + 1) / n);
      job.control.set_progress(0.0);
      try {
        job_analysis(requests[i], view, output, artifacts, &job.control);
        status[i]["state"] = "ready";
      } catch (const AnalysisRejected& e) {
        status[i]["state"] = "failed";
        status[i]["error"] = e.what();
      } catch (const Error& e) {
        if (e.code() == ErrorCode::cancelled) throw;
        status[i]["state"] = "failed";
        status[i]["error"] = e.what();
      } catch (const std::exception& e) {
        // One analysis going wrong costs only its own entry, not the volume.
        spdlog::error("job {}: analysis {} failed: {}", id, requests[i].artifact_key(), log_safe(e.what()));
        status[i]["state"] = "failed";
        status[i]["error"] = "the analysis failed unexpectedly; it was logged";
      }
    }
    job.control.set_span(0.0, 1.0);
    return status;
  }

  // A job taken from the queue becomes running only once its record says
  // so: a client that saw "running" then learns after a kill and a restart
  // that it was interrupted while running. False if it was cancelled
  // meanwhile (the cancellation's own record is written after this one).
  bool mark_running(Job& job) {
    std::lock_guard guard(job.store_mutex);
    JobSnapshot s;
    {
      std::lock_guard lock(mutex);
      if (job.snap.state != JobState::queued) return false;
      s = job.snap;
    }
    s.state = JobState::running;
    s.started_at = format_time(Clock::now());
    if (!job.ephemeral && !job.removed) {
      try {
        store->save(s);
      } catch (const std::exception& e) {
        spdlog::error("job {}: cannot write its record: {}", s.id, e.what());
      }
    }
    std::lock_guard lock(mutex);
    if (job.snap.state != JobState::queued) return false;
    job.snap.state = JobState::running;
    job.snap.started_at = s.started_at;
    announce(job.snap);
    return true;
  }

  void work() {
    for (;;) {
      const std::optional<std::string> id = queue->take();
      if (!id) return;  // closed: the service stops
      std::shared_ptr<Job> job;
      PreparedVoxelJob prepared;
      {
        std::lock_guard lock(mutex);
        auto it = jobs.find(*id);
        if (it == jobs.end() || it->second->snap.state != JobState::queued || !it->second->prepared) {
          queue->ack(*id);  // cancelled while waiting
          continue;
        }
        job = it->second;
        prepared = std::move(*job->prepared);
        job->prepared.reset();
      }
      if (!mark_running(*job)) {  // cancelled meanwhile
        queue->ack(*id);
        continue;
      }
      deliver();
      const auto t0 = std::chrono::steady_clock::now();
      JobSnapshot done;
      try {
        const std::vector<api::AnalysisRequest> analyses = prepared.params.analyses;
        // With analyses to prepare, voxelizing is the first half of the bar.
        if (!analyses.empty()) job->control.set_span(0.0, 0.5);
        JobOutput output;
        VoxelJobResult r;
        if (prepared.streamed) {
          // Slab by slab straight into the stored RLE: the grid is never whole.
          const Grid grid = prepared.grid;
          const std::int64_t slab_layers = prepared.slab_layers;
          // A job of values writes them beside its bits, both at once.
          const std::optional<ValueVolume> type = prepared.params.value_type();
          store->write_volume(job->snap.id, [&](ByteSink& bits_sink) {
            BitSlabWriter bits(grid, VolumeFormat::rle, EncodeOptions{}, bits_sink);
            const BitSlabConsumer to_bits = [&](std::int64_t k0, const BitVolume& slab) { bits.write(k0, slab); };
            if (!type) {
              r = execute_streamed_voxel_job(std::move(prepared), /*with_report=*/true, &job->control, engine_threads,
                                             slab_layers, to_bits);
            } else {
              store->write_layer(job->snap.id, "values", *type, [&](ByteSink& values_sink) {
                ValueSlabWriter values(grid, *type, VolumeFormat::rle, EncodeOptions{}, values_sink);
                r = execute_streamed_voxel_job(
                    std::move(prepared), /*with_report=*/true, &job->control, engine_threads, slab_layers, to_bits,
                    [&](std::int64_t k0, const ValueVolume& slab) { values.write(k0, slab); });
                values.finish();
              });
            }
            bits.finish();
          });
          output.rle = store->volume_rle(job->snap.id);
          if (type) output.values_rle = store->layer_rle(job->snap.id, "values");
        } else {
          r = execute_voxel_job(std::move(prepared), /*with_report=*/!job->ephemeral, &job->control, engine_threads);
          output.solid = std::make_shared<const BitVolume>(std::move(r.volume));
          if (r.values) output.values = std::make_shared<const ValueVolume>(std::move(*r.values));
          for (auto& [name, layer] : r.layers)
            output.layers.emplace_back(name, std::make_shared<const ValueVolume>(std::move(layer)));
          if (!job->ephemeral) {
            store->save_volume(job->snap.id, *output.solid);
            if (output.values) store->save_layer(job->snap.id, "values", *output.values);
            for (const auto& [name, layer] : output.layers) store->save_layer(job->snap.id, name, *layer);
          }
        }
        nlohmann::json analyses_done = prepare_analyses(*job, analyses, r, output);
        std::lock_guard lock(mutex);
        JobSnapshot& s = job->snap;
        if (!analyses.empty()) s.analyses = std::move(analyses_done);
        s.state = JobState::succeeded;
        s.progress = 1.0;
        s.mesh = r.report;
        s.mesh_mass = r.mesh_mass;
        for (auto& t : r.timings.stages)
          if (std::none_of(s.timings.begin(), s.timings.end(), [&](const auto& x) { return x.first == t.first; }))
            s.timings.push_back(t);
        s.filled_voxels = r.filled;
        s.values = r.values_info.is_null() ? nlohmann::json(nullptr) : r.values_info;
        if (job->ephemeral) {
          job->result = output;
        } else {
          cache_put(s.id, output);
          succeeded_by_hash[s.content_hash] = s.id;
        }
      } catch (const Error& e) {
        std::lock_guard lock(mutex);
        JobSnapshot& s = job->snap;
        if (e.code() == ErrorCode::cancelled) {
          s.state = job->stopped_by_shutdown ? JobState::failed : JobState::cancelled;
          if (job->stopped_by_shutdown) s.failure = interrupted("running");
        } else {
          s.state = JobState::failed;
          const api::ErrorKind& kind = api::error_kind(e.code());
          if (!kind.client_message) spdlog::error("job {}: {}", s.id, log_safe(e.what()));
          s.failure = JobFailure{kind.slug, "The job failed",
                                 kind.client_message ? e.what() : "the job failed unexpectedly; it was logged"};
        }
      } catch (const StorageFull& e) {
        // Nothing half-written stays: the disk is not kept full by this job.
        spdlog::error("job {}: cannot store its result: {}", job->snap.id, e.what());
        std::lock_guard guard(job->store_mutex);
        if (!job->removed) store->remove(job->snap.id);
        std::lock_guard lock(mutex);
        job->snap.state = JobState::failed;
        job->snap.failure = JobFailure{"storage-full", "The service's storage is full",
                                       "the result could not be stored: " + std::string(e.what()) + "; retry later"};
      } catch (const std::exception& e) {
        spdlog::error("job {}: internal error: {}", job->snap.id, log_safe(e.what()));
        std::lock_guard lock(mutex);
        job->snap.state = JobState::failed;
        job->snap.failure = JobFailure{"internal", "Internal error", "the job failed unexpectedly; it was logged"};
      }
      {
        std::lock_guard lock(mutex);
        job->snap.finished_at = format_time(Clock::now());
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        recent_job_seconds = 0.8 * recent_job_seconds + 0.2 * seconds;
        done = job->snap;
        announce(done);
      }
      job->memory.release();
      persist(*job, done);
      queue->ack(*id);
      deliver();
      finished_cv.notify_all();
    }
  }

  std::size_t expire() {
    const auto now = Clock::now();
    std::vector<std::shared_ptr<Job>> victims;
    {
      std::lock_guard lock(mutex);
      for (const auto& [id, job] : jobs)
        if (expired(job->snap, now, config.result_ttl)) victims.push_back(job);
      for (const auto& job : victims) forget(job->snap.id);
    }
    for (const auto& job : victims) remove_from_store(*job);
    return victims.size();
  }

  void remove_from_store(Job& job) const {
    std::lock_guard guard(job.store_mutex);
    job.removed = true;
    store->remove(job.snap.id);
  }

  // Requires the lock.
  void forget(const std::string& id) {
    auto it = jobs.find(id);
    if (it == jobs.end()) return;
    auto h = succeeded_by_hash.find(it->second->snap.content_hash);
    if (h != succeeded_by_hash.end() && h->second == id) succeeded_by_hash.erase(h);
    cache.drop_job(id);
    jobs.erase(it);
  }

  int retry_after() const {
    const int workers_n = std::max<int>(1, static_cast<int>(workers.size()));
    const double seconds = recent_job_seconds * static_cast<double>(queue->depth() + 1) / workers_n;
    return std::clamp(static_cast<int>(std::ceil(seconds)), 1, 3600);
  }

  std::shared_ptr<Job> enqueue(std::vector<std::uint8_t>& mesh_bytes, const std::string& name_hint,
                               const nlohmann::json& params_json, bool ephemeral, JobSnapshot* cached_out,
                               std::uint64_t max_voxels = 0);
};

JobManager::JobManager(JobManagerConfig config) : impl_(std::make_unique<Impl>(std::move(config))) {
  Impl& m = *impl_;
  // Jobs a previous process left queued or running are reported failed with
  // reason "interrupted" rather than silently re-run: a client polling them
  // learns what happened and decides whether to resubmit.
  for (JobSnapshot s : m.store->load_all()) {
    if (!finished(s.state)) {
      s.failure = interrupted(s.state == JobState::queued ? "queued" : "running");
      s.state = JobState::failed;
      s.finished_at = format_time(Clock::now());
      m.store->save(s);
    }
    if (s.state == JobState::succeeded) {
      auto prev = m.succeeded_by_hash.find(s.content_hash);
      if (prev == m.succeeded_by_hash.end() || m.jobs.at(prev->second)->snap.created_at < s.created_at)
        m.succeeded_by_hash[s.content_hash] = s.id;
    }
    auto job = std::make_shared<Job>();
    job->snap = std::move(s);
    m.jobs.emplace(job->snap.id, job);
  }
  const int n = m.config.workers > 0 ? m.config.workers : default_thread_count();
  // Each job's engine may use every core: a lone big job should not wait on
  // idle cores, and two concurrent ones share them through the scheduler.
  m.engine_threads = 0;
  for (int i = 0; i < n; ++i) m.workers.emplace_back([&m] { m.work(); });
  m.expiry = std::make_unique<ExpiryTimer>(m.config.result_ttl, [&m] { m.expire(); });
}

JobManager::~JobManager() { shutdown(std::chrono::seconds(0)); }

std::shared_ptr<Job> JobManager::Impl::enqueue(std::vector<std::uint8_t>& mesh_bytes, const std::string& name_hint,
                                               const nlohmann::json& params_json, bool ephemeral,
                                               JobSnapshot* cached_out, std::uint64_t max_voxels) {
  {
    std::lock_guard lock(mutex);
    if (!accepting) throw NotAccepting("the service is shutting down and accepts no new jobs");
    if (queue->depth() >= config.queue_size)
      throw QueueFull("the job queue is full (" + std::to_string(config.queue_size) + " jobs waiting); retry later",
                      retry_after());
  }
  const auto parsed = std::make_shared<const api::JobParams>(api::parse_job_params(params_json));
  const api::JobParams& params = *parsed;
  if (!ephemeral && store->free_bytes() < config.min_free_disk)
    throw StorageFull("the service's disk has less than " + std::to_string(config.min_free_disk >> 20) +
                      " MiB free and takes no new jobs until results expire or are deleted; retry later");
  // Synchronous jobs are never stored, so never answered from the store: they
  // skip the hash (a tenth of a small job's time).
  const std::string hash = ephemeral ? std::string() : content_hash(mesh_bytes, params_json.dump());

  // An identical earlier submission that succeeded answers this one.
  if (!ephemeral && cached_out) {
    std::optional<JobSnapshot> original;
    {
      std::lock_guard lock(mutex);
      auto h = succeeded_by_hash.find(hash);
      if (h != succeeded_by_hash.end()) original = jobs.at(h->second)->snap;
    }
    if (original) {
      JobSnapshot s = *original;
      s.id = new_job_id();
      s.created_at = s.started_at = s.finished_at = format_time(Clock::now());
      s.params = params_json;
      s.job = parsed;
      s.cached = true;
      s.timings.clear();
      s.analyses = analyses_status(params.analyses, s.id, "on_request");
      try {
        store->share_volume(original->id, s.id);
        store->save(s);
        auto job = std::make_shared<Job>();
        job->snap = s;
        {
          std::lock_guard lock(mutex);
          jobs.emplace(s.id, job);
        }
        *cached_out = s;
        return nullptr;
      } catch (const std::exception& e) {
        // The original was deleted meanwhile: fall through and compute.
        store->remove(s.id);
        spdlog::info("job cache miss for {}: {}", original->id, e.what());
      }
    }
  }

  if (ephemeral && !params.analyses.empty())
    throw api::InvalidParams(std::vector<api::FieldError>{
        {"/analyses", "synchronous voxelization answers with the volume only; submit to POST /v1/jobs for analyses"}});
  // The upload while it is decoded, then the job's own share: until the
  // decoded mesh is known, a bound from the bytes and the format.
  MemoryBudget::Reservation decoding =
      budget.reserve(decode_memory_estimate(mesh_bytes, name_hint, config.limits.decode), "decoding this upload");
  JobLimits limits = config.limits;
  // A job that would not fit the per-job memory whole streams where it can;
  // a synchronous one is never stored, so never streamed.
  limits.stream_above_bytes = ephemeral ? 0 : std::min(limits.stream_above_bytes, config.max_job_memory);
  limits.stream_slab_bytes = std::min(limits.stream_slab_bytes, config.max_job_memory / 4);
  PreparedVoxelJob prepared = prepare_voxel_job(mesh_bytes, name_hint, params, limits);
  if (max_voxels > 0 && prepared.grid.voxel_count() > max_voxels)
    throw Error(ErrorCode::limit_exceeded, "the grid has " + std::to_string(prepared.grid.voxel_count()) +
                                               " voxels; synchronous voxelization takes at most " +
                                               std::to_string(max_voxels) + ": submit it to POST /v1/jobs instead");
  if (prepared.memory_estimate > config.max_job_memory)
    throw Error(ErrorCode::limit_exceeded,
                "the job needs about " + std::to_string(prepared.memory_estimate >> 20) + " MiB for its volumes, over the limit of " +
                    std::to_string(config.max_job_memory >> 20) + " MiB; use a lower resolution or a larger voxel_size");
  std::uint64_t analyses_peak = 0;
  for (const api::AnalysisRequest& r : params.analyses) {
    try {
      analyses_peak = std::max(analyses_peak, analysis_memory_on_job(r, prepared.grid, prepared.streamed, config.max_job_memory));
    } catch (const Error& e) {
      throw Error(e.code(), std::string("analyses: ") + e.what());
    }
  }
  mesh_bytes.clear();
  mesh_bytes.shrink_to_fit();
  decoding.release();
  MemoryBudget::Reservation memory =
      budget.reserve(mesh_memory(prepared.mesh) + prepared.memory_estimate + analyses_peak, "the job");

  auto job = std::make_shared<Job>();
  job->memory = std::move(memory);
  job->ephemeral = ephemeral;
  JobSnapshot& s = job->snap;
  s.id = new_job_id();
  s.state = JobState::queued;
  s.created_at = format_time(Clock::now());
  s.params = params_json;
  s.job = parsed;
  s.mesh_format = to_string(prepared.format);
  s.triangles = prepared.triangles;
  s.grid = prepared.grid;
  s.streamed = prepared.streamed;
  s.timings = prepared.timings.stages;
  s.content_hash = hash;
  s.analyses = analyses_status(params.analyses, s.id, "pending");
  job->prepared = std::move(prepared);
  // Recorded before a worker can see it, so the final record always wins. A
  // job that cannot be recorded is not accepted (a full disk is a 507).
  if (!ephemeral) store->save(s);
  {
    std::lock_guard lock(mutex);
    // Queued under the table's lock: a worker that takes it at once finds it.
    const bool closing = !accepting;
    if (closing || !queue->submit(s.id)) {
      const int wait = retry_after();
      if (!ephemeral) store->remove(s.id);
      if (closing) throw NotAccepting("the service is shutting down and accepts no new jobs");
      throw QueueFull("the job queue is full (" + std::to_string(config.queue_size) + " jobs waiting); retry later", wait);
    }
    jobs.emplace(s.id, job);
    announce(s);
  }
  deliver();
  return job;
}

JobSnapshot JobManager::submit(std::vector<std::uint8_t> mesh_bytes, const std::string& name_hint,
                               const nlohmann::json& params_json) {
  JobSnapshot cached;
  auto job = impl_->enqueue(mesh_bytes, name_hint, params_json, false, &cached);
  if (!job) {
    {
      std::lock_guard lock(impl_->mutex);
      impl_->announce(cached);
    }
    impl_->deliver();
    return cached;
  }
  std::lock_guard lock(impl_->mutex);
  return impl_->snapshot_of(*job);
}

std::optional<JobSnapshot> JobManager::get(const std::string& id) const {
  std::lock_guard lock(impl_->mutex);
  auto it = impl_->jobs.find(id);
  if (it == impl_->jobs.end() || it->second->ephemeral) return std::nullopt;
  return impl_->snapshot_of(*it->second);
}

std::vector<JobSnapshot> JobManager::list(std::size_t offset, std::size_t limit, std::size_t* total) const {
  std::vector<JobSnapshot> all;
  {
    std::lock_guard lock(impl_->mutex);
    for (const auto& [id, job] : impl_->jobs)
      if (!job->ephemeral) all.push_back(impl_->snapshot_of(*job));
  }
  std::sort(all.begin(), all.end(), [](const JobSnapshot& a, const JobSnapshot& b) {
    return a.created_at != b.created_at ? a.created_at > b.created_at : a.id > b.id;
  });
  if (total) *total = all.size();
  if (offset >= all.size()) return {};
  const auto first = all.begin() + static_cast<std::ptrdiff_t>(offset);
  return {first, first + static_cast<std::ptrdiff_t>(std::min(limit, all.size() - offset))};
}

JobManager::RemoveResult JobManager::cancel_or_delete(const std::string& id) {
  std::optional<JobSnapshot> cancelled;
  std::shared_ptr<Job> target;
  {
    std::lock_guard lock(impl_->mutex);
    auto it = impl_->jobs.find(id);
    if (it == impl_->jobs.end() || it->second->ephemeral) return RemoveResult::not_found;
    target = it->second;
    Job& job = *target;
    if (job.snap.state == JobState::queued) {
      impl_->queue->cancel(id);
      job.snap.state = JobState::cancelled;
      job.snap.finished_at = format_time(Clock::now());
      job.prepared.reset();
      job.memory.release();
      cancelled = job.snap;
      impl_->announce(job.snap);
    } else if (job.snap.state == JobState::running) {
      job.control.request_cancel();  // the worker records the end state
      return RemoveResult::cancelled;
    } else {
      impl_->forget(id);
    }
  }
  if (cancelled) {
    impl_->persist(*target, *cancelled);
    impl_->deliver();
    impl_->finished_cv.notify_all();
    return RemoveResult::cancelled;
  }
  impl_->remove_from_store(*target);
  return RemoveResult::deleted;
}

std::optional<std::string> JobManager::load_artifact(const std::string& id, const std::string& key) const {
  return impl_->store->load_artifact(id, key);
}

void JobManager::save_artifact(const std::string& id, const std::string& key, const std::string& bytes) {
  std::shared_ptr<Job> job;
  {
    std::lock_guard lock(impl_->mutex);
    auto it = impl_->jobs.find(id);
    if (it == impl_->jobs.end() || it->second->ephemeral) return;
    job = it->second;
  }
  std::lock_guard guard(job->store_mutex);
  if (job->removed) return;  // deleted meanwhile: do not bring its directory back
  try {
    impl_->store->save_artifact(id, key, bytes);
  } catch (const std::exception& e) {
    spdlog::warn("job {}: cannot keep artifact {}: {}", id, key, e.what());
  }
}

std::shared_ptr<const BitVolume> JobManager::volume(const std::string& id) {
  {
    std::lock_guard lock(impl_->mutex);
    auto it = impl_->jobs.find(id);
    if (it == impl_->jobs.end() || it->second->snap.state != JobState::succeeded) return nullptr;
  }
  if (auto v = impl_->cache.get<BitVolume>(id)) return v;
  auto v = impl_->store->load_volume(id);
  if (v) {
    std::lock_guard lock(impl_->mutex);
    if (impl_->jobs.count(id)) impl_->cache.put(id, v, v->byte_size());
  }
  return v;
}

std::shared_ptr<const MappedFile> JobManager::volume_rle(const std::string& id) {
  {
    std::lock_guard lock(impl_->mutex);
    auto it = impl_->jobs.find(id);
    if (it == impl_->jobs.end() || it->second->snap.state != JobState::succeeded) return nullptr;
  }
  return impl_->store->volume_rle(id);
}

std::shared_ptr<const MappedFile> JobManager::values_rle(const std::string& id) {
  {
    std::lock_guard lock(impl_->mutex);
    auto it = impl_->jobs.find(id);
    if (it == impl_->jobs.end() || it->second->snap.state != JobState::succeeded || !it->second->snap.has_value_volume())
      return nullptr;
  }
  return impl_->store->layer_rle(id, "values");
}

std::uint64_t JobManager::max_job_memory() const { return impl_->config.max_job_memory; }

std::shared_ptr<const ValueVolume> JobManager::values(const std::string& id) {
  {
    std::lock_guard lock(impl_->mutex);
    auto it = impl_->jobs.find(id);
    if (it == impl_->jobs.end() || !it->second->snap.has_value_volume()) return nullptr;
  }
  return layer(id, "values");
}

std::shared_ptr<const ValueVolume> JobManager::layer(const std::string& id, const std::string& name) {
  const std::string key = VolumeCache::layer_key(id, name);
  {
    std::lock_guard lock(impl_->mutex);
    auto it = impl_->jobs.find(id);
    if (it == impl_->jobs.end() || it->second->snap.state != JobState::succeeded) return nullptr;
  }
  if (auto v = impl_->cache.get<ValueVolume>(key)) return v;
  auto v = impl_->store->load_layer(id, name);
  if (v) {
    std::lock_guard lock(impl_->mutex);
    if (impl_->jobs.count(id)) impl_->cache.put(key, v, byte_size(*v));
  }
  return v;
}

JobOutput JobManager::run_sync(std::vector<std::uint8_t> mesh_bytes, const std::string& name_hint,
                               const nlohmann::json& params_json, JobSnapshot* snapshot, std::uint64_t max_voxels,
                               const std::function<bool()>& abandoned) {
  std::shared_ptr<Job> job = impl_->enqueue(mesh_bytes, name_hint, params_json, true, nullptr, max_voxels);
  std::unique_lock lock(impl_->mutex);
  bool cancelled = false;
  while (!impl_->finished_cv.wait_for(lock, std::chrono::milliseconds(100), [&] { return finished(job->snap.state); })) {
    if (cancelled || !abandoned) continue;
    lock.unlock();
    const bool gone = abandoned();
    lock.lock();
    if (!gone || finished(job->snap.state)) continue;
    cancelled = true;
    spdlog::info("job {}: the client of a synchronous request went away; cancelling", job->snap.id);
    if (job->snap.state == JobState::queued) {
      impl_->queue->cancel(job->snap.id);
      job->snap.state = JobState::cancelled;  // the worker skips it
      job->snap.finished_at = format_time(Clock::now());
      job->prepared.reset();
      job->memory.release();
    } else {
      job->control.request_cancel();
    }
  }
  if (snapshot) *snapshot = job->snap;
  impl_->jobs.erase(job->snap.id);
  return job->snap.state == JobState::succeeded ? job->result : JobOutput{};
}

JobCounts JobManager::counts() const {
  JobCounts c;
  std::lock_guard lock(impl_->mutex);
  for (const auto& [id, job] : impl_->jobs) {
    switch (job->snap.state) {
      case JobState::queued: ++c.queued; break;
      case JobState::running: ++c.running; break;
      case JobState::succeeded: ++c.succeeded; break;
      case JobState::failed: ++c.failed; break;
      case JobState::cancelled: ++c.cancelled; break;
    }
  }
  c.queue_depth = impl_->queue->depth();
  return c;
}

MemoryBudget::Reservation JobManager::reserve_memory(std::uint64_t bytes, const std::string& what) {
  return impl_->budget.reserve(bytes, what);
}

std::uint64_t JobManager::memory_budget() const { return impl_->budget.total(); }
std::uint64_t JobManager::memory_in_use() const { return impl_->budget.used(); }
bool JobManager::storage_ok() const { return impl_->store->free_bytes() >= impl_->config.min_free_disk; }

bool JobManager::accepting() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->accepting;
}

void JobManager::shutdown(std::chrono::seconds deadline) {
  Impl& m = *impl_;
  std::vector<JobSnapshot> abandoned;
  {
    std::unique_lock lock(m.mutex);
    if (m.shut_down) return;
    m.shut_down = true;
    m.accepting = false;
    // Queued jobs will not run in this process: record them as interrupted.
    for (const std::string& id : m.queue->close()) {
      auto it = m.jobs.find(id);
      if (it == m.jobs.end()) continue;
      const std::shared_ptr<Job>& job = it->second;
      if (job->snap.state != JobState::queued) continue;
      job->snap.state = JobState::failed;
      job->snap.failure = interrupted("queued");
      job->snap.finished_at = format_time(Clock::now());
      job->prepared.reset();
      job->memory.release();
      abandoned.push_back(job->snap);
      m.announce(job->snap);
    }
    auto running = [&] {
      for (const auto& [id, job] : m.jobs)
        if (job->snap.state == JobState::running) return true;
      return false;
    };
    if (!m.finished_cv.wait_for(lock, deadline, [&] { return !running(); })) {
      for (auto& [id, job] : m.jobs)
        if (job->snap.state == JobState::running) {
          job->stopped_by_shutdown = true;
          job->control.request_cancel();
        }
      m.finished_cv.wait(lock, [&] { return !running(); });
    }
  }
  for (const auto& s : abandoned) m.store->save(s);
  m.deliver();
  m.finished_cv.notify_all();
  for (auto& t : m.workers) t.join();
  m.expiry.reset();
}

std::size_t JobManager::expire_now() { return impl_->expire(); }

}  // namespace voxd::server
