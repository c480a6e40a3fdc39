#pragma once
// Prometheus text-format metrics (exposition format 0.0.4): jobs by state,
// queue depth, stage durations, HTTP traffic and rejections, per-tenant
// traffic and quota refusals, webhook deliveries.
#include <atomic>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <tuple>
#include <vector>

#include "server/jobs/job.h"

namespace voxd::server {

class Metrics {
 public:
  void count_request(const std::string& method, const std::string& route, int status);
  void count_rejected(const std::string& reason);
  // Per tenant, by the names of the tenants file only (the unnamed tenant
  // is not labelled): requests that named it, jobs it submitted, and
  // requests its quotas refused (by quota).
  void count_tenant_request(const std::string& tenant);
  void count_tenant_job(const std::string& tenant);
  void count_tenant_rejected(const std::string& tenant, const std::string& quota);
  // Webhook deliveries by outcome: delivered, retried, failed (gave up).
  void count_webhook(const std::string& outcome);
  void observe_stage(const std::string& stage, double seconds);
  void add_bytes_in(std::uint64_t n) { bytes_in_ += n; }
  void add_bytes_out(std::uint64_t n) { bytes_out_ += n; }
  // Event streams (GET /v1/jobs/{id}/events) open now.
  void stream_opened() { ++event_streams_; }
  void stream_closed() { --event_streams_; }
  std::string render(const JobCounts& jobs) const;

 private:
  struct Histogram {
    std::vector<std::uint64_t> buckets;  // cumulative counts per bound
    std::uint64_t count = 0;
    double sum = 0;
  };
  static const std::vector<double>& bounds();
  mutable std::mutex mutex_;
  std::map<std::tuple<std::string, std::string, int>, std::uint64_t> requests_;
  std::map<std::string, std::uint64_t> rejected_;
  std::map<std::string, std::uint64_t> tenant_requests_, tenant_jobs_, webhooks_;
  std::map<std::pair<std::string, std::string>, std::uint64_t> tenant_rejected_;
  std::map<std::string, Histogram> stages_;
  std::atomic<std::uint64_t> bytes_in_{0}, bytes_out_{0};
  std::atomic<std::int64_t> event_streams_{0};
};

}  // namespace voxd::server
