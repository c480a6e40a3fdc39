#pragma once
// Callbacks waiting to be delivered, kept where the jobs are (the data
// directory, or the shared Redis) so that a delivery outlives the process
// that queued it: at least once. A delivery is claimed for a lease while it
// is sent; one whose sender died is claimed again when the lease ends.
#include <chrono>
#include <cstdint>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

namespace voxd::server {

struct WebhookDelivery {
  std::string id;  // the job's id: one delivery per job (receivers dedupe on it)
  std::string tenant;
  std::string url;
  std::string event;  // "job.finished"
  std::string body;   // the job's final status JSON
  int attempts = 0;   // made so far

  nlohmann::json to_json() const;
  static WebhookDelivery from_json(const nlohmann::json& j);  // throws on a malformed one
};

class WebhookOutbox {
 public:
  virtual ~WebhookOutbox() = default;
  // Queues it, due now; a second add of the same id is ignored (a job's end
  // announced twice is delivered once).
  virtual void add(const WebhookDelivery& delivery) = 0;
  // A due delivery, claimed for `lease`; nothing when none is due.
  virtual std::optional<WebhookDelivery> claim(std::chrono::milliseconds lease) = 0;
  // Delivered, or given up on: gone.
  virtual void done(const std::string& id) = 0;
  // Tried and failed: kept (with its attempts) and due again after `delay`.
  virtual void retry(const WebhookDelivery& delivery, std::chrono::milliseconds delay) = 0;
};

}  // namespace voxd::server
