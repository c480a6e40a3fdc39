// The job engine's facade: the service's backend chosen once, a synchronous
// backend beside it, the workers and the expiry timer started, and each
// call handed to the part that answers it (admission, a backend, the table).
#include "server/jobs/job_manager.h"

#include <spdlog/spdlog.h>

#include "server/jobs/embedded_backend.h"
#include "server/jobs/expiry.h"
#include "server/jobs/job_engine.h"
#include "server/jobs/job_store.h"
#include "server/jobs/synchronous_backend.h"
#include "voxd/parallel.h"

namespace voxd::server {

struct JobManager::Impl {
  explicit Impl(JobManagerConfig config) : engine(std::move(config)), synchronous(engine) {
    backend = engine.config.backend ? engine.config.backend(engine) : std::make_unique<EmbeddedJobBackend>(engine);
  }
  JobEngine engine;
  std::unique_ptr<JobBackend> backend;  // the service's jobs
  SynchronousJobBackend synchronous;    // POST /v1/voxelize
  std::vector<std::thread> workers;
  std::unique_ptr<ExpiryTimer> expiry;  // sweeps expired jobs until shutdown
  bool shut_down = false;               // under engine.mutex

  bool succeeded(const std::string& id) const {
    const auto s = backend->find(id);
    return s && s->state == JobState::succeeded;
  }
  // Caches a volume read back for a job, and drops it again when the job
  // was removed meanwhile: removal forgets the job and drops its entries
  // (embedded: both under the table's lock; replicated: the record first),
  // so either that drop comes after this put or this check sees the job
  // gone, and a deleted job's volume never stays cached.
  template <class T>
  void cache_while_kept(const std::string& id, const std::string& key, const std::shared_ptr<const T>& v,
                        std::uint64_t bytes) {
    engine.cache.put(key, v, bytes);
    if (!succeeded(id)) engine.cache.drop_job(id);
  }
};

JobManager::JobManager(JobManagerConfig config) : impl_(std::make_unique<Impl>(std::move(config))) {
  Impl& m = *impl_;
  const int n = m.engine.config.workers > 0 ? m.engine.config.workers : default_thread_count();
  m.engine.worker_count = static_cast<std::size_t>(n);
  // Each job's engine may use every core: a lone big job should not wait on
  // idle cores, and two concurrent ones share them through the scheduler.
  m.engine.engine_threads = 0;
  for (int i = 0; i < n; ++i) m.workers.emplace_back([&m] { m.engine.work(*m.backend); });
  m.expiry = std::make_unique<ExpiryTimer>(m.engine.config.result_ttl, [&m] { m.backend->expire(); });
  m.backend->start();
}

JobManager::~JobManager() { shutdown(std::chrono::seconds(0)); }

JobSnapshot JobManager::submit(std::vector<std::uint8_t> mesh_bytes, const std::string& name_hint,
                               const nlohmann::json& params_json, const JobLabels& labels) {
  JobEngine& e = impl_->engine;
  JobSnapshot cached;
  std::shared_ptr<Job> job = e.admit(*impl_->backend, mesh_bytes, name_hint, labels, params_json, &cached, 0);
  if (!job) {
    {
      std::lock_guard lock(e.mutex);
      e.announce(cached);
    }
    e.deliver();
    return cached;
  }
  std::lock_guard lock(e.mutex);
  return e.snapshot_of(*job);
}

std::optional<JobSnapshot> JobManager::get(const std::string& id) const { return impl_->backend->find(id); }

std::uint64_t JobManager::wait_for_change(std::uint64_t seen, std::chrono::milliseconds timeout) const {
  JobEngine& e = impl_->engine;
  std::unique_lock lock(e.mutex);
  e.changed_cv.wait_for(lock, timeout, [&] { return e.changes != seen; });
  return e.changes;
}

std::vector<JobSnapshot> JobManager::list(std::size_t offset, std::size_t limit, std::size_t* total,
                                          const JobFilter& filter) const {
  return impl_->backend->list(offset, limit, total, filter);
}

TenantUsage JobManager::usage(const std::string& tenant) const { return impl_->backend->usage(tenant); }

JobManager::RemoveResult JobManager::cancel_or_delete(const std::string& id) { return impl_->backend->cancel_or_delete(id); }

std::optional<std::string> JobManager::load_artifact(const std::string& id, const std::string& key) const {
  return impl_->backend->store()->load_artifact(id, key);
}

bool JobManager::load_artifact_into(const std::string& id, const std::string& key, std::span<char> out) const {
  return impl_->backend->store()->load_artifact_into(id, key, out);
}

void JobManager::save_artifact(const std::string& id, const std::string& key, std::string_view bytes) {
  impl_->backend->save_artifact(id, key, bytes);
}

std::shared_ptr<const BitVolume> JobManager::volume(const std::string& id) {
  if (!impl_->succeeded(id)) return nullptr;
  VolumeCache& cache = impl_->engine.cache;
  if (auto v = cache.get<BitVolume>(id)) return v;
  auto v = impl_->backend->store()->load_volume(id);
  if (v) impl_->cache_while_kept(id, id, v, v->byte_size());
  return v;
}

std::shared_ptr<const StoredBlob> JobManager::volume_rle(const std::string& id) {
  if (!impl_->succeeded(id)) return nullptr;
  return impl_->backend->store()->volume_rle(id);
}

std::shared_ptr<const StoredBlob> JobManager::values_rle(const std::string& id) {
  const auto s = impl_->backend->find(id);
  if (!s || s->state != JobState::succeeded || !s->has_value_volume()) return nullptr;
  return impl_->backend->store()->layer_rle(id, "values");
}

std::uint64_t JobManager::max_job_memory() const { return impl_->engine.config.max_job_memory; }

std::shared_ptr<const ValueVolume> JobManager::values(const std::string& id) {
  const auto s = impl_->backend->find(id);
  if (!s || !s->has_value_volume()) return nullptr;
  return layer(id, "values");
}

std::shared_ptr<const ValueVolume> JobManager::layer(const std::string& id, const std::string& name) {
  const std::string key = VolumeCache::layer_key(id, name);
  if (!impl_->succeeded(id)) return nullptr;
  VolumeCache& cache = impl_->engine.cache;
  if (auto v = cache.get<ValueVolume>(key)) return v;
  auto v = impl_->backend->store()->load_layer(id, name);
  if (v) impl_->cache_while_kept(id, key, v, byte_size(*v));
  return v;
}

JobOutput JobManager::run_sync(std::vector<std::uint8_t> mesh_bytes, const std::string& name_hint,
                               const nlohmann::json& params_json, JobSnapshot* snapshot, std::uint64_t max_voxels,
                               const std::function<bool()>& abandoned) {
  JobEngine& e = impl_->engine;
  std::shared_ptr<Job> job = e.admit(impl_->synchronous, mesh_bytes, name_hint, JobLabels{}, params_json, nullptr, max_voxels);
  std::unique_lock lock(e.mutex);
  bool cancelled = false;
  while (!e.finished_cv.wait_for(lock, std::chrono::milliseconds(100), [&] { return finished(job->snap.state); })) {
    if (cancelled || !abandoned) continue;
    lock.unlock();
    const bool gone = abandoned();
    lock.lock();
    if (!gone || finished(job->snap.state)) continue;
    cancelled = true;
    spdlog::info("job {}: the client of a synchronous request went away; cancelling", job->snap.id);
    if (job->snap.state == JobState::queued) {
      e.local_queue->cancel(job->snap.id);
      job->snap.state = JobState::cancelled;  // the worker skips it
      job->snap.finished_at = format_now();
      job->prepared.reset();
      job->memory.release();
    } else {
      job->control.request_cancel();
    }
  }
  if (snapshot) *snapshot = job->snap;
  e.jobs.erase(job->snap.id);
  return job->snap.state == JobState::succeeded ? job->result : JobOutput{};
}

JobCounts JobManager::counts() const { return impl_->backend->counts(); }

MemoryBudget::Reservation JobManager::reserve_memory(std::uint64_t bytes, const std::string& what) {
  return impl_->engine.budget.reserve(bytes, what);
}

std::uint64_t JobManager::memory_budget() const { return impl_->engine.budget.total(); }
std::uint64_t JobManager::memory_in_use() const { return impl_->engine.budget.used(); }

std::optional<std::string> JobManager::storage_full() const {
  const JobStore* store = impl_->backend->store();
  try {
    if (store->free_bytes() >= impl_->engine.config.min_free_disk) return std::nullopt;
    return store->full_reason();
  } catch (const std::exception& e) {
    impl_->engine.warn_backend(e);
    return "the shared backend (Redis) is unreachable";
  }
}

bool JobManager::backend_ok() const { return impl_->backend->reachable(); }

bool JobManager::accepting() const {
  std::lock_guard lock(impl_->engine.mutex);
  return impl_->engine.accepting;
}

void JobManager::shutdown(std::chrono::seconds deadline) {
  Impl& m = *impl_;
  JobEngine& e = m.engine;
  std::vector<std::pair<JobStore*, JobSnapshot>> abandoned;
  {
    std::unique_lock lock(e.mutex);
    if (m.shut_down) return;
    m.shut_down = true;
    e.accepting = false;
    // Queued jobs will not run in this process: record them as interrupted.
    // (A shared queue's stay there, for the other replicas.)
    std::vector<std::string> left = e.local_queue->close();
    m.backend->close();
    for (const std::string& id : left) {
      auto it = e.jobs.find(id);
      if (it == e.jobs.end()) continue;
      const std::shared_ptr<Job>& job = it->second;
      if (job->snap.state != JobState::queued) continue;
      job->snap.state = JobState::failed;
      job->snap.failure = interrupted("queued");
      job->snap.finished_at = format_now();
      job->prepared.reset();
      job->memory.release();
      abandoned.emplace_back(job->backend->store(), job->snap);
      e.announce(job->snap);
    }
    auto running = [&] {
      for (const auto& [id, job] : e.jobs)
        if (job->snap.state == JobState::running) return true;
      return false;
    };
    if (!e.finished_cv.wait_for(lock, deadline, [&] { return !running(); })) {
      for (auto& [id, job] : e.jobs)
        if (job->snap.state == JobState::running) {
          job->stopped_by_shutdown = true;
          job->control.request_cancel();
        }
      e.finished_cv.wait(lock, [&] { return !running(); });
    }
  }
  for (const auto& [store, s] : abandoned)
    if (store) store->save(s);  // synchronous jobs are never stored
  e.deliver();
  e.finished_cv.notify_all();
  for (auto& t : m.workers) t.join();
  m.expiry.reset();
  m.backend->stop();
}

std::size_t JobManager::expire_now() { return impl_->backend->expire(); }

}  // namespace voxd::server
