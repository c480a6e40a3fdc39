#include "server/http/metrics.h"

#include <sstream>

namespace voxd::server {

const std::vector<double>& Metrics::bounds() {
  static const std::vector<double> b = {0.001, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1, 2.5, 5, 10, 30, 60, 300};
  return b;
}

void Metrics::count_request(const std::string& method, const std::string& route, int status) {
  std::lock_guard lock(mutex_);
  ++requests_[{method, route, status}];
}

void Metrics::count_rejected(const std::string& reason) {
  std::lock_guard lock(mutex_);
  ++rejected_[reason];
}

void Metrics::count_tenant_request(const std::string& tenant) {
  if (tenant.empty()) return;
  std::lock_guard lock(mutex_);
  ++tenant_requests_[tenant];
}

void Metrics::count_tenant_job(const std::string& tenant) {
  if (tenant.empty()) return;
  std::lock_guard lock(mutex_);
  ++tenant_jobs_[tenant];
}

void Metrics::count_tenant_rejected(const std::string& tenant, const std::string& quota) {
  if (tenant.empty()) return;
  std::lock_guard lock(mutex_);
  ++tenant_rejected_[{tenant, quota}];
}

void Metrics::count_webhook(const std::string& outcome) {
  std::lock_guard lock(mutex_);
  ++webhooks_[outcome];
}

void Metrics::observe_stage(const std::string& stage, double seconds) {
  std::lock_guard lock(mutex_);
  Histogram& h = stages_[stage];
  if (h.buckets.empty()) h.buckets.assign(bounds().size(), 0);
  for (std::size_t i = 0; i < bounds().size(); ++i)
    if (seconds <= bounds()[i]) ++h.buckets[i];
  ++h.count;
  h.sum += seconds;
}

std::string Metrics::render(const JobCounts& jobs) const {
  std::ostringstream o;
  o << "# HELP voxd_jobs Jobs known to the service, by state.\n# TYPE voxd_jobs gauge\n";
  const std::pair<const char*, std::uint64_t> states[] = {{"queued", jobs.queued},
                                                          {"running", jobs.running},
                                                          {"succeeded", jobs.succeeded},
                                                          {"failed", jobs.failed},
                                                          {"cancelled", jobs.cancelled}};
  for (const auto& [name, n] : states) o << "voxd_jobs{state=\"" << name << "\"} " << n << '\n';
  o << "# HELP voxd_queue_depth Jobs waiting for a worker.\n# TYPE voxd_queue_depth gauge\n";
  o << "voxd_queue_depth " << jobs.queue_depth << '\n';
  if (jobs.live_replicas) {
    o << "# HELP voxd_replicas_live Replicas sharing this service's Redis that reported in the last 5 s.\n"
         "# TYPE voxd_replicas_live gauge\n";
    o << "voxd_replicas_live " << *jobs.live_replicas << '\n';
  }
  o << "# HELP voxd_event_streams_open Event streams open on this replica (at most --max-event-streams).\n"
       "# TYPE voxd_event_streams_open gauge\n";
  o << "voxd_event_streams_open " << event_streams_.load() << '\n';
  o << "# HELP voxd_http_bytes_received_total Request body bytes received.\n# TYPE voxd_http_bytes_received_total counter\n";
  o << "voxd_http_bytes_received_total " << bytes_in_.load() << '\n';
  o << "# HELP voxd_http_bytes_sent_total Response body bytes sent.\n# TYPE voxd_http_bytes_sent_total counter\n";
  o << "voxd_http_bytes_sent_total " << bytes_out_.load() << '\n';
  std::lock_guard lock(mutex_);
  o << "# HELP voxd_http_requests_total HTTP requests by method, route and status.\n# TYPE voxd_http_requests_total counter\n";
  for (const auto& [key, n] : requests_)
    o << "voxd_http_requests_total{method=\"" << std::get<0>(key) << "\",route=\"" << std::get<1>(key) << "\",status=\""
      << std::get<2>(key) << "\"} " << n << '\n';
  o << "# HELP voxd_rejected_requests_total Requests refused, by reason.\n# TYPE voxd_rejected_requests_total counter\n";
  for (const auto& [reason, n] : rejected_) o << "voxd_rejected_requests_total{reason=\"" << reason << "\"} " << n << '\n';
  if (!tenant_requests_.empty()) {
    o << "# HELP voxd_tenant_requests_total /v1 requests by tenant (names from the tenants file).\n"
         "# TYPE voxd_tenant_requests_total counter\n";
    for (const auto& [tenant, n] : tenant_requests_) o << "voxd_tenant_requests_total{tenant=\"" << tenant << "\"} " << n << '\n';
  }
  if (!tenant_jobs_.empty()) {
    o << "# HELP voxd_tenant_jobs_submitted_total Jobs accepted by tenant.\n# TYPE voxd_tenant_jobs_submitted_total counter\n";
    for (const auto& [tenant, n] : tenant_jobs_) o << "voxd_tenant_jobs_submitted_total{tenant=\"" << tenant << "\"} " << n << '\n';
  }
  if (!tenant_rejected_.empty()) {
    o << "# HELP voxd_tenant_quota_rejections_total Requests a tenant's quota refused (429), by quota.\n"
         "# TYPE voxd_tenant_quota_rejections_total counter\n";
    for (const auto& [key, n] : tenant_rejected_)
      o << "voxd_tenant_quota_rejections_total{tenant=\"" << key.first << "\",quota=\"" << key.second << "\"} " << n << '\n';
  }
  o << "# HELP voxd_webhook_deliveries_total Webhook delivery attempts by outcome.\n# TYPE voxd_webhook_deliveries_total counter\n";
  for (const char* outcome : {"delivered", "retried", "failed"}) {
    auto it = webhooks_.find(outcome);
    o << "voxd_webhook_deliveries_total{outcome=\"" << outcome << "\"} " << (it == webhooks_.end() ? 0 : it->second) << '\n';
  }
  o << "# HELP voxd_stage_duration_seconds Duration of job stages.\n# TYPE voxd_stage_duration_seconds histogram\n";
  for (const auto& [stage, h] : stages_) {
    for (std::size_t i = 0; i < bounds().size(); ++i)
      o << "voxd_stage_duration_seconds_bucket{stage=\"" << stage << "\",le=\"" << bounds()[i] << "\"} " << h.buckets[i] << '\n';
    o << "voxd_stage_duration_seconds_bucket{stage=\"" << stage << "\",le=\"+Inf\"} " << h.count << '\n';
    o << "voxd_stage_duration_seconds_sum{stage=\"" << stage << "\"} " << h.sum << '\n';
    o << "voxd_stage_duration_seconds_count{stage=\"" << stage << "\"} " << h.count << '\n';
  }
  return o.str();
}

}  // namespace voxd::server
