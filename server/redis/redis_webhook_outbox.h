#pragma once
// The outbox of replicas sharing one Redis: PREFIX webhooks (hash: delivery
// id -> the delivery's JSON) and PREFIX webhooks:due (sorted set: id -> due
// time in ms by Redis's clock, so replicas' clocks need not agree). A claim
// moves the due time past its lease in one script: one replica sends it,
// and another takes it when that one dies mid-way.
#include <memory>
#include <string>

#include "server/redis/redis_client.h"
#include "server/webhooks/webhook_outbox.h"

namespace voxd::server {

class RedisWebhookOutbox final : public WebhookOutbox {
 public:
  RedisWebhookOutbox(std::shared_ptr<RedisPool> pool, std::string prefix);
  void add(const WebhookDelivery& delivery) override;
  std::optional<WebhookDelivery> claim(std::chrono::milliseconds lease) override;
  void done(const std::string& id) override;
  void retry(const WebhookDelivery& delivery, std::chrono::milliseconds delay) override;

 private:
  std::shared_ptr<RedisPool> pool_;
  const std::string hash_, due_;
};

}  // namespace voxd::server
