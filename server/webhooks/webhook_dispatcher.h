#pragma once
// Delivers jobs' callbacks: a job that ends with a callback URL gets one
// delivery in the outbox (webhook_outbox.h); this thread sends each due one
// as POST <url> with the job's final status as its JSON body and
//   X-Voxd-Event: job.finished
//   X-Voxd-Delivery: <job id>           (the same on every retry)
//   X-Voxd-Signature: t=<unix s>,v1=<hex HMAC-SHA256(tenant secret, "t.body")>
// A 2xx answer delivers it; anything else (or no answer in 10 s) is tried
// again after 1, 2, 4 … 256 s, ten attempts in all, then given up and logged.
// Redirects are not followed, and the URL's host and port are checked
// against the allow-list again before each attempt (it may have shrunk).
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>

#include "server/jobs/job.h"
#include "server/tenants/tenant_directory.h"
#include "server/webhooks/webhook_outbox.h"

namespace voxd::server {

class Metrics;

struct WebhookTiming {
  int max_attempts = 10;
  std::chrono::milliseconds first_retry{1000};    // doubled after each failure...
  std::chrono::milliseconds max_retry{256000};    // ...up to this
  std::chrono::milliseconds lease{60000};         // a claimed delivery's, while it is sent
  std::chrono::seconds timeout{10};               // connect, send and answer, each
};

class WebhookDispatcher {
 public:
  WebhookDispatcher(std::shared_ptr<WebhookOutbox> outbox, TenantDirectory& tenants, Metrics& metrics,
                    WebhookTiming timing = {});
  ~WebhookDispatcher();  // stop()
  // A job that ended: queues its callback, if it names one.
  void job_ended(const JobSnapshot& job);
  void stop();

 private:
  void run();
  bool deliver_one();  // false when nothing was due
  // True when delivered; else why not, and whether that is final.
  bool send(const WebhookDelivery& d, std::string* why, bool* final);

  std::shared_ptr<WebhookOutbox> outbox_;
  TenantDirectory& tenants_;
  Metrics& metrics_;
  const WebhookTiming timing_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  std::chrono::steady_clock::time_point last_warning_{};  // the dispatcher thread's
  std::thread thread_;
};

}  // namespace voxd::server
