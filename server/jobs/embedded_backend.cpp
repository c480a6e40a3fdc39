#include "server/jobs/embedded_backend.h"

#include <algorithm>

#include <spdlog/spdlog.h>

#include "server/jobs/expiry.h"
#include "server/jobs/job_engine.h"
#include "server/jobs/local_job_store.h"

namespace voxd::server {

EmbeddedJobBackend::EmbeddedJobBackend(JobEngine& engine)
    : engine_(engine), store_(std::make_shared<LocalJobStore>(engine.config.data_dir)) {
  // Jobs a previous process left queued or running are reported failed with
  // reason "interrupted" rather than silently re-run: a client polling them
  // learns what happened and decides whether to resubmit.
  std::lock_guard lock(engine_.mutex);
  for (JobSnapshot s : store_->load_all()) {
    if (!finished(s.state)) {
      s.failure = interrupted(s.state == JobState::queued ? "queued" : "running");
      s.state = JobState::failed;
      s.finished_at = format_now();
      store_->save(s);
    }
    if (s.state == JobState::succeeded) {
      auto prev = succeeded_by_hash_.find(s.content_hash);
      if (prev == succeeded_by_hash_.end() || engine_.jobs.at(prev->second)->snap.created_at < s.created_at)
        succeeded_by_hash_[s.content_hash] = s.id;
    }
    auto job = std::make_shared<Job>();
    job->backend = this;
    job->snap = std::move(s);
    engine_.jobs.emplace(job->snap.id, job);
  }
}

std::size_t EmbeddedJobBackend::waiting() const { return engine_.local_queue->depth(); }

std::optional<JobSnapshot> EmbeddedJobBackend::earlier_success(const std::string& hash) const {
  std::lock_guard lock(engine_.mutex);
  auto h = succeeded_by_hash_.find(hash);
  if (h == succeeded_by_hash_.end()) return std::nullopt;
  return engine_.jobs.at(h->second)->snap;
}

void EmbeddedJobBackend::keep_answered(const JobSnapshot& s) {
  auto job = std::make_shared<Job>();
  job->backend = this;
  job->snap = s;
  std::lock_guard lock(engine_.mutex);
  engine_.jobs.emplace(s.id, job);
}

void EmbeddedJobBackend::accept(Admitted admitted) { engine_.enqueue_local(admitted, store_.get()); }

JobBackend::Next EmbeddedJobBackend::next(std::shared_ptr<Job>& job, PreparedVoxelJob& prepared) {
  const std::optional<TakenJob> taken = engine_.local_queue->take(std::chrono::seconds(1));
  if (!taken) return engine_.local_queue->closed() ? Next::stopped : Next::none;
  job = engine_.take_local(taken->id, prepared);
  return job ? Next::job : Next::none;
}

bool EmbeddedJobBackend::record_running(Job& job, const JobSnapshot& running) {
  if (job.removed) return true;
  try {
    store_->save(running);
  } catch (const std::exception& e) {
    spdlog::error("job {}: cannot write its record: {}", running.id, e.what());
  }
  return true;
}

void EmbeddedJobBackend::drop_taken(Job& job) { engine_.local_queue->ack(job.snap.id); }

void EmbeddedJobBackend::succeeded(Job& job, const JobOutput& output) {
  engine_.cache_put(job.snap.id, output);
  succeeded_by_hash_[job.snap.content_hash] = job.snap.id;
}

void EmbeddedJobBackend::discard_partial(Job& job) {
  std::lock_guard guard(job.store_mutex);
  if (!job.removed) store_->remove(job.snap.id);
}

void EmbeddedJobBackend::ended(const JobSnapshot& done) { engine_.announce(done); }

void EmbeddedJobBackend::close_out(Job& job, const JobSnapshot& done, bool) {
  persist(job, done);
  engine_.local_queue->ack(done.id);
}

void EmbeddedJobBackend::persist(Job& job, const JobSnapshot& s) const {
  std::lock_guard guard(job.store_mutex);
  if (job.removed) return;
  try {
    store_->save(s);
  } catch (const std::exception& e) {
    spdlog::error("job {}: cannot write its record: {}", s.id, e.what());
  }
}

void EmbeddedJobBackend::remove_from_store(Job& job) const {
  std::lock_guard guard(job.store_mutex);
  job.removed = true;
  store_->remove(job.snap.id);
}

void EmbeddedJobBackend::forget(const std::string& id) {
  auto it = engine_.jobs.find(id);
  if (it == engine_.jobs.end()) return;
  auto h = succeeded_by_hash_.find(it->second->snap.content_hash);
  if (h != succeeded_by_hash_.end() && h->second == id) succeeded_by_hash_.erase(h);
  engine_.cache.drop_job(id);
  engine_.jobs.erase(it);
}

std::optional<JobSnapshot> EmbeddedJobBackend::find(const std::string& id) const {
  std::lock_guard lock(engine_.mutex);
  auto it = engine_.jobs.find(id);
  if (it == engine_.jobs.end() || it->second->backend != this) return std::nullopt;
  return engine_.snapshot_of(*it->second);
}

std::vector<JobSnapshot> EmbeddedJobBackend::list(std::size_t offset, std::size_t limit, std::size_t* total,
                                                  const JobFilter& filter) const {
  std::vector<JobSnapshot> all;
  {
    std::lock_guard lock(engine_.mutex);
    for (const auto& [id, job] : engine_.jobs)
      if (job->backend == this && filter.matches(job->snap)) all.push_back(engine_.snapshot_of(*job));
  }
  std::sort(all.begin(), all.end(), [](const JobSnapshot& a, const JobSnapshot& b) {
    return a.created_at != b.created_at ? a.created_at > b.created_at : a.id > b.id;
  });
  if (total) *total = all.size();
  if (offset >= all.size()) return {};
  const auto first = all.begin() + static_cast<std::ptrdiff_t>(offset);
  return {first, first + static_cast<std::ptrdiff_t>(std::min(limit, all.size() - offset))};
}

RemoveResult EmbeddedJobBackend::cancel_or_delete(const std::string& id) {
  std::optional<JobSnapshot> cancelled;
  std::shared_ptr<Job> target;
  {
    std::lock_guard lock(engine_.mutex);
    auto it = engine_.jobs.find(id);
    if (it == engine_.jobs.end() || it->second->backend != this) return RemoveResult::not_found;
    target = it->second;
    Job& job = *target;
    if (job.snap.state == JobState::queued) {
      engine_.local_queue->cancel(id);
      job.snap.state = JobState::cancelled;
      job.snap.finished_at = format_now();
      job.prepared.reset();
      job.memory.release();
      cancelled = job.snap;
      engine_.announce(job.snap);
    } else if (job.snap.state == JobState::running) {
      job.control.request_cancel();  // the worker records the end state
      return RemoveResult::cancelled;
    } else {
      forget(id);
    }
  }
  if (cancelled) {
    persist(*target, *cancelled);
    engine_.deliver();
    engine_.finished_cv.notify_all();
    return RemoveResult::cancelled;
  }
  remove_from_store(*target);
  return RemoveResult::deleted;
}

void EmbeddedJobBackend::save_artifact(const std::string& id, const std::string& key, std::string_view bytes) {
  std::shared_ptr<Job> job;
  {
    std::lock_guard lock(engine_.mutex);
    auto it = engine_.jobs.find(id);
    if (it == engine_.jobs.end() || it->second->backend != this) return;
    job = it->second;
  }
  std::lock_guard guard(job->store_mutex);
  if (job->removed) return;  // deleted meanwhile: do not bring its directory back
  try {
    store_->save_artifact(id, key, bytes);
  } catch (const std::exception& e) {
    spdlog::warn("job {}: cannot keep artifact {}: {}", id, key, e.what());
  }
}

TenantUsage EmbeddedJobBackend::usage(const std::string& tenant) const {
  TenantUsage u;
  std::lock_guard lock(engine_.mutex);
  for (const auto& [id, job] : engine_.jobs) {
    const JobSnapshot& s = job->snap;
    if (job->backend != this || s.labels.tenant != tenant) continue;
    if (s.state == JobState::queued) ++u.queued;
    if (s.state == JobState::running) ++u.running;
    if (s.state == JobState::succeeded) u.stored_bytes += s.stored_bytes;
  }
  return u;
}

JobCounts EmbeddedJobBackend::counts() const {
  JobCounts c;
  std::lock_guard lock(engine_.mutex);
  // Every job this process holds, synchronous ones while they run included.
  for (const auto& [id, job] : engine_.jobs) {
    switch (job->snap.state) {
      case JobState::queued: ++c.queued; break;
      case JobState::running: ++c.running; break;
      case JobState::succeeded: ++c.succeeded; break;
      case JobState::failed: ++c.failed; break;
      case JobState::cancelled: ++c.cancelled; break;
    }
  }
  c.queue_depth = engine_.local_queue->depth();
  return c;
}

std::size_t EmbeddedJobBackend::expire() {
  const auto now = std::chrono::system_clock::now();
  std::vector<std::shared_ptr<Job>> victims;
  {
    std::lock_guard lock(engine_.mutex);
    for (const auto& [id, job] : engine_.jobs)
      if (job->backend == this && expired(job->snap, now, engine_.config.result_ttl)) victims.push_back(job);
    for (const auto& job : victims) forget(job->snap.id);
  }
  for (const auto& job : victims) remove_from_store(*job);
  return victims.size();
}

}  // namespace voxd::server
