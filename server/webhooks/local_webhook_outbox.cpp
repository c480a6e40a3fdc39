#include "server/webhooks/local_webhook_outbox.h"

#include <fstream>
#include <sstream>

#include <spdlog/spdlog.h>

namespace voxd::server {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

nlohmann::json WebhookDelivery::to_json() const {
  return {{"id", id}, {"tenant", tenant}, {"url", url}, {"event", event}, {"body", body}, {"attempts", attempts}};
}

WebhookDelivery WebhookDelivery::from_json(const nlohmann::json& j) {
  return WebhookDelivery{j.at("id"), j.at("tenant"), j.at("url"), j.at("event"), j.at("body"), j.at("attempts")};
}

LocalWebhookOutbox::LocalWebhookOutbox(fs::path dir) : dir_(std::move(dir)) {
  fs::create_directories(dir_);
  for (const auto& entry : fs::directory_iterator(dir_)) {
    if (entry.path().extension() != ".json") {
      std::error_code ignored;
      fs::remove(entry.path(), ignored);  // a write cut short
      continue;
    }
    due_[entry.path().stem().string()] = Clock::now();
  }
  if (!due_.empty()) spdlog::info("webhooks: {} deliveries kept from before the restart", due_.size());
}

void LocalWebhookOutbox::write(const WebhookDelivery& delivery) const {
  const fs::path tmp = path(delivery.id).string() + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out << delivery.to_json().dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
    out.flush();
    if (!out) throw std::runtime_error("cannot write " + tmp.string());
  }
  fs::rename(tmp, path(delivery.id));
}

void LocalWebhookOutbox::add(const WebhookDelivery& delivery) {
  std::lock_guard lock(mutex_);
  if (due_.count(delivery.id) || fs::exists(path(delivery.id))) return;
  write(delivery);
  due_[delivery.id] = Clock::now();
}

std::optional<WebhookDelivery> LocalWebhookOutbox::claim(std::chrono::milliseconds lease) {
  std::lock_guard lock(mutex_);
  const auto now = Clock::now();
  for (auto& [id, due] : due_) {
    if (due > now) continue;
    std::ifstream in(path(id), std::ios::binary);
    std::stringstream text;
    text << in.rdbuf();
    try {
      WebhookDelivery d = WebhookDelivery::from_json(nlohmann::json::parse(text.str()));
      due = now + lease;
      return d;
    } catch (const std::exception& e) {
      spdlog::warn("webhooks: dropping unreadable delivery {}: {}", id, e.what());
      std::error_code ignored;
      fs::remove(path(id), ignored);
      due_.erase(id);
      return std::nullopt;
    }
  }
  return std::nullopt;
}

void LocalWebhookOutbox::done(const std::string& id) {
  std::lock_guard lock(mutex_);
  std::error_code ignored;
  fs::remove(path(id), ignored);
  due_.erase(id);
}

void LocalWebhookOutbox::retry(const WebhookDelivery& delivery, std::chrono::milliseconds delay) {
  std::lock_guard lock(mutex_);
  write(delivery);
  due_[delivery.id] = Clock::now() + delay;
}

}  // namespace voxd::server
