#pragma once
// The embedded outbox: one file a delivery under DATA/webhooks, written
// atomically; the due times and leases are in memory (after a restart every
// kept delivery is due at once).
#include <filesystem>
#include <map>
#include <mutex>

#include "server/webhooks/webhook_outbox.h"

namespace voxd::server {

class LocalWebhookOutbox final : public WebhookOutbox {
 public:
  explicit LocalWebhookOutbox(std::filesystem::path dir);
  void add(const WebhookDelivery& delivery) override;
  std::optional<WebhookDelivery> claim(std::chrono::milliseconds lease) override;
  void done(const std::string& id) override;
  void retry(const WebhookDelivery& delivery, std::chrono::milliseconds delay) override;

 private:
  void write(const WebhookDelivery& delivery) const;
  std::filesystem::path path(const std::string& id) const { return dir_ / (id + ".json"); }

  const std::filesystem::path dir_;
  std::mutex mutex_;
  std::map<std::string, std::chrono::steady_clock::time_point> due_;  // id -> due
};

}  // namespace voxd::server
