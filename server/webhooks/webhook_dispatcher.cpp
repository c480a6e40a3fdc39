#include "server/webhooks/webhook_dispatcher.h"

#include <httplib.h>
#include <spdlog/spdlog.h>

#include "server/http/job_status.h"
#include "server/http/metrics.h"
#include "server/log_safe.h"
#include "server/webhooks/webhook_signature.h"
#include "server/webhooks/webhook_url.h"

namespace voxd::server {

// How often the outbox is looked at when nothing woke the thread: other
// replicas' deliveries and retries come due without a wake-up here.
constexpr std::chrono::milliseconds kPoll{500};

WebhookDispatcher::WebhookDispatcher(std::shared_ptr<WebhookOutbox> outbox, TenantDirectory& tenants, Metrics& metrics,
                                     WebhookTiming timing)
    : outbox_(std::move(outbox)), tenants_(tenants), metrics_(metrics), timing_(timing), thread_([this] { run(); }) {}

WebhookDispatcher::~WebhookDispatcher() { stop(); }

void WebhookDispatcher::stop() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void WebhookDispatcher::job_ended(const JobSnapshot& job) {
  if (!finished(job.state) || job.labels.callback.empty()) return;
  WebhookDelivery d;
  d.id = job.id;
  d.tenant = job.labels.tenant;
  d.url = job.labels.callback;
  d.event = "job.finished";
  d.body = job_status_json(job).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  try {
    outbox_->add(d);
  } catch (const std::exception& e) {
    spdlog::error("webhooks: job {}: cannot queue its callback: {}", job.id, log_safe(e.what()));
    return;
  }
  wake_.notify_all();
}

void WebhookDispatcher::run() {
  for (;;) {
    {
      std::lock_guard lock(mutex_);
      if (stopping_) return;
    }
    bool busy = false;
    try {
      busy = deliver_one();
    } catch (const std::exception& e) {
      // The outbox (Redis) is away: tried again every poll, said once a minute.
      const auto now = std::chrono::steady_clock::now();
      if (now - last_warning_ >= std::chrono::minutes(1)) {
        last_warning_ = now;
        spdlog::warn("webhooks: cannot reach the outbox: {}", log_safe(e.what()));
      }
    }
    if (busy) continue;
    std::unique_lock lock(mutex_);
    wake_.wait_for(lock, kPoll, [&] { return stopping_; });
  }
}

bool WebhookDispatcher::send(const WebhookDelivery& d, std::string* why, bool* final) {
  *final = true;  // what no retry mends
  const std::optional<WebhookUrl> url = parse_webhook_url(d.url, why);
  if (!url) return false;
  if (!tenants_.webhook_host_allowed(url->host, url->port)) {
    *why = "its host is no longer in the webhook allow-list";
    return false;
  }
  const std::optional<Tenant> tenant = tenants_.find(d.tenant);
  if (!tenant || tenant->webhook_secret.empty()) {
    *why = "its tenant has no webhook secret any more";
    return false;
  }
  *final = false;
  const std::string host = url->host.find(':') != std::string::npos ? "[" + url->host + "]" : url->host;
  httplib::Client client(url->scheme + "://" + host + ":" + std::to_string(url->port));
  client.set_follow_location(false);
  client.set_connection_timeout(timing_.timeout);
  client.set_read_timeout(timing_.timeout);
  client.set_write_timeout(timing_.timeout);
  client.set_keep_alive(false);
  const auto now = std::chrono::duration_cast<std::chrono::seconds>(std::chrono::system_clock::now().time_since_epoch()).count();
  const httplib::Headers headers = {{"User-Agent", "voxd-webhook/1"},
                                    {"X-Voxd-Event", d.event},
                                    {"X-Voxd-Delivery", d.id},
                                    {"X-Voxd-Signature", webhook_signature(tenant->webhook_secret, now, d.body)}};
  const httplib::Result r = client.Post(url->target, headers, d.body, "application/json");
  if (!r) {
    *why = "no answer: " + httplib::to_string(r.error());
    return false;
  }
  if (r->status < 200 || r->status > 299) {
    *why = "it answered " + std::to_string(r->status);
    return false;
  }
  return true;
}

bool WebhookDispatcher::deliver_one() {
  std::optional<WebhookDelivery> d = outbox_->claim(timing_.lease);
  if (!d) return false;
  std::string why;
  bool final = false;
  if (send(*d, &why, &final)) {
    outbox_->done(d->id);
    metrics_.count_webhook("delivered");
    spdlog::info("webhooks: job {} delivered to its callback (attempt {})", d->id, d->attempts + 1);
    return true;
  }
  ++d->attempts;
  if (final || d->attempts >= timing_.max_attempts) {
    outbox_->done(d->id);
    metrics_.count_webhook("failed");
    spdlog::warn("webhooks: job {}: gave up on its callback after {} attempts: {}", d->id, d->attempts, log_safe(why));
    return true;
  }
  auto delay = timing_.first_retry * (1LL << std::min(d->attempts - 1, 20));
  if (delay > timing_.max_retry) delay = timing_.max_retry;
  outbox_->retry(*d, delay);
  metrics_.count_webhook("retried");
  spdlog::info("webhooks: job {}: callback attempt {} failed ({}); again in {} ms", d->id, d->attempts, log_safe(why), delay.count());
  return true;
}

}  // namespace voxd::server
