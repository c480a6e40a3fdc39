#include "server/redis/redis_webhook_outbox.h"

#include <spdlog/spdlog.h>

namespace voxd::server {
namespace {

// KEYS: hash, due. ARGV: id, delivery JSON, delay ms ("0": now), "1" to
// add only a new one. Redis's own clock.
constexpr const char* kPut = R"lua(
local t = redis.call('TIME')
local now = tonumber(t[1]) * 1000 + math.floor(tonumber(t[2]) / 1000)
if ARGV[4] == '1' then
  if redis.call('HSETNX', KEYS[1], ARGV[1], ARGV[2]) == 0 then return 0 end
else
  redis.call('HSET', KEYS[1], ARGV[1], ARGV[2])
end
redis.call('ZADD', KEYS[2], now + tonumber(ARGV[3]), ARGV[1])
return 1
)lua";

// KEYS: hash, due. ARGV: lease ms. The first due delivery, its due time
// moved past the lease; nil when none is due.
constexpr const char* kClaim = R"lua(
local t = redis.call('TIME')
local now = tonumber(t[1]) * 1000 + math.floor(tonumber(t[2]) / 1000)
local ids = redis.call('ZRANGEBYSCORE', KEYS[2], '-inf', now, 'LIMIT', 0, 1)
if #ids == 0 then return false end
local body = redis.call('HGET', KEYS[1], ids[1])
if not body then
  redis.call('ZREM', KEYS[2], ids[1])
  return false
end
redis.call('ZADD', KEYS[2], now + tonumber(ARGV[1]), ids[1])
return body
)lua";

}  // namespace

RedisWebhookOutbox::RedisWebhookOutbox(std::shared_ptr<RedisPool> pool, std::string prefix)
    : pool_(std::move(pool)), hash_(prefix + "webhooks"), due_(prefix + "webhooks:due") {}

void RedisWebhookOutbox::add(const WebhookDelivery& delivery) {
  const std::string json = delivery.to_json().dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  pool_->command({"EVAL", kPut, "2", hash_, due_, delivery.id, json, "0", "1"});
}

std::optional<WebhookDelivery> RedisWebhookOutbox::claim(std::chrono::milliseconds lease) {
  const RedisReply r = pool_->command({"EVAL", kClaim, "2", hash_, due_, std::to_string(lease.count())});
  if (r.is_nil()) return std::nullopt;
  try {
    return WebhookDelivery::from_json(nlohmann::json::parse(r.text()));
  } catch (const std::exception& e) {
    spdlog::warn("webhooks: dropping an unreadable delivery: {}", e.what());
    return std::nullopt;  // its lease keeps it away for now; it is retried and dropped again
  }
}

void RedisWebhookOutbox::done(const std::string& id) { pool_->pipeline({{"HDEL", hash_, id}, {"ZREM", due_, id}}); }

void RedisWebhookOutbox::retry(const WebhookDelivery& delivery, std::chrono::milliseconds delay) {
  const std::string json = delivery.to_json().dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  pool_->command({"EVAL", kPut, "2", hash_, due_, delivery.id, json, std::to_string(delay.count()), "0"});
}

}  // namespace voxd::server
