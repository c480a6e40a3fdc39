#include "server/jobs/synchronous_backend.h"

#include "server/jobs/job_engine.h"

namespace voxd::server {

std::size_t SynchronousJobBackend::waiting() const { return engine_.local_queue->depth(); }

void SynchronousJobBackend::accept(Admitted admitted) { engine_.enqueue_local(admitted, nullptr); }

void SynchronousJobBackend::drop_taken(Job& job) { engine_.local_queue->ack(job.snap.id); }

void SynchronousJobBackend::succeeded(Job& job, const JobOutput& output) { job.result = output; }

void SynchronousJobBackend::ended(const JobSnapshot& done) { engine_.announce(done); }

void SynchronousJobBackend::close_out(Job&, const JobSnapshot& done, bool) { engine_.local_queue->ack(done.id); }

}  // namespace voxd::server
