// `voxd serve`: the HTTP service with its embedded defaults.
#include <malloc.h>
#include <pthread.h>
#include <signal.h>

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <iostream>
#include <random>
#include <thread>

#include <httplib.h>
#include <spdlog/spdlog.h>

#include "server/cli/cli.h"
#include "server/cli/cli_args.h"
#include "server/draco_isolation.h"
#include "server/pipeline/job_pipeline.h"
#include "server/http/connection_server.h"
#include "server/http/http_api.h"
#include "server/http/metrics.h"
#include "server/http/routes.h"
#include "server/http/stream_requests.h"
#include "server/cli/cli_serve_config.h"
#include "server/jobs/job_manager.h"
#include "server/jobs/replicated_backend.h"
#include "server/redis/redis_job_queue.h"
#include "server/redis/redis_job_store.h"
#include "server/json_log.h"
#include "server/log_safe.h"
#include "server/redis/redis_webhook_outbox.h"
#include "server/tenants/tenant_directory.h"
#include "server/webhooks/local_webhook_outbox.h"
#include "server/webhooks/webhook_dispatcher.h"
#include "voxd/error.h"

namespace voxd::cli {

int serve_command(int argc, char** argv) {
  using namespace voxd::server;
  for (int i = 2; i < argc; ++i)
    if (std::string(argv[i]) == "--help") {
      std::cout << serve_help();
      return 0;
    }
  const ServeConfig config = parse_serve_config(argc, argv, 2);
  if (config.log_format == "json")
    use_json_log_lines();
  else
    spdlog::set_pattern("%Y-%m-%dT%H:%M:%S.%eZ %l %v", spdlog::pattern_time_type::utc);
  // JSON log lines carry their message as a JSON value.
  auto log = [&](const std::string& text) {
    if (config.log_format == "json") spdlog::info(nlohmann::json(text).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
    else spdlog::info(text);
  };

  // Signals are taken by one thread with sigwait; every thread started after
  // this inherits the mask, so none is interrupted at a random point.
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGTERM);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGHUP);  // reads the tenants file again
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);

  // Buffers of 1 MiB and more (uploads, decoded meshes, analyses' arrays)
  // are mapped on their own and unmapped when freed. glibc otherwise raises
  // this threshold to 32 MiB after the first large free, after which such
  // buffers come from per-thread arenas that keep them: 20 uploads over 16
  // HTTP threads held 700 MB after they were refused.
  ::mallopt(M_MMAP_THRESHOLD, 1 << 20);
  // Fixing that threshold also fixes the trim threshold at glibc's 128 KiB:
  // every thread's arena then handed its free top back to the kernel after
  // each small job (madvise) and faulted it in again for the next, 330
  // page faults and 0.3 ms of a 10,000-triangle job's 3.5 ms of CPU
  // (docs/benchmarks.md, issue #39). An arena keeps up to 8 MiB of free top
  // now, blocks under 1 MiB only; the large ones are still unmapped.
  ::mallopt(M_TRIM_THRESHOLD, 8 << 20);

  Metrics metrics;
  JobManagerConfig jc;
  jc.workers = config.workers;
  jc.queue_size = config.queue_size;
  jc.data_dir = config.data_dir;
  jc.limits.decode.max_bytes = config.max_upload_bytes;
  jc.limits.decode.max_triangles = config.max_triangles;
  jc.limits.max_voxels = config.max_voxels;
  jc.limits.device = config.device;
  jc.limits.max_streamed_voxels = config.max_streamed_voxels;
  DracoIsolation draco;
  draco.max_triangles = config.max_triangles;
  draco.max_memory = config.max_decode_memory;
  jc.limits.decode.draco_decoder = [draco](std::span<const std::uint8_t> data) {
    DracoIsolation sized = draco;
    sized.max_memory = std::min(draco.max_memory, draco_child_memory(data.size()));
    return decode_draco_isolated(data, sized);
  };
  jc.memory_budget = config.memory_budget;
  jc.min_free_disk = config.min_free_disk;
  jc.max_job_memory = config.max_job_memory;
  jc.result_ttl = std::chrono::seconds(config.result_ttl);
  std::unique_ptr<TenantDirectory> tenants;
  try {
    tenants = std::make_unique<TenantDirectory>(config.tenants_file, config.api_keys, config.webhook_hosts, config.webhook_secret);
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("--tenants: ") + e.what());
  }
  std::shared_ptr<WebhookOutbox> outbox;
  if (!config.redis_url.empty()) {
    // Scale-out: queue, records and results on the shared Redis.
    char host[256] = {};
    ::gethostname(host, sizeof host - 1);
    const std::string replica =
        std::string(host) + ":" + std::to_string(::getpid()) + ":" + std::to_string(std::random_device{}() % 100000);
    auto pool = std::make_shared<RedisPool>(parse_redis_url(config.redis_url));
    RedisBackendOptions ro;
    ro.result_ttl = std::chrono::seconds(config.result_ttl);
    ro.inflight_ttl = std::max<std::chrono::milliseconds>(std::chrono::hours(24), ro.result_ttl);
    ro.max_result_bytes = config.max_result_bytes;
    ro.replica_id = replica;
    auto store = std::make_shared<RedisJobStore>(pool, ro);
    RedisQueueOptions qo;
    qo.consumer = replica;
    qo.capacity = config.queue_size;
    qo.lease = std::chrono::seconds(config.redis_lease);
    ReplicatedBackendParts parts;
    parts.queue = std::make_shared<RedisJobQueue>(pool, qo);
    parts.store = store;
    parts.records = store;
    parts.max_deliveries = config.max_deliveries;
    parts.slab_tasks = store;
    parts.slab_task_bytes = config.slab_task_bytes;
    jc.backend = replicated_backend(std::move(parts));
    outbox = std::make_shared<RedisWebhookOutbox>(pool, ro.prefix);
    jc.max_result_bytes = config.max_result_bytes;
    log("shared backend: Redis at " + pool->url().redacted() + " as replica " + replica +
        (store->reachable() ? "" : " (not reachable yet: not ready until it is)"));
  }
  if (!outbox) outbox = std::make_shared<LocalWebhookOutbox>(std::filesystem::path(config.data_dir) / "webhooks");
  // Declared before the jobs: it takes their ends until they are shut down.
  WebhookDispatcher webhooks(outbox, *tenants, metrics);
  jc.on_state_change = [&](const JobSnapshot& s) {
    webhooks.job_ended(s);
    if (s.state == JobState::succeeded || s.state == JobState::failed)
      for (const auto& [stage, seconds] : s.timings) metrics.observe_stage(stage, seconds);
    if (config.log_format == "json")
      spdlog::info(nlohmann::json{{"event", "job"}, {"id", s.id}, {"state", to_string(s.state)},
                                  {"error", s.failure ? s.failure->detail : ""}}
                       .dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
    else
      spdlog::info("job {} {}{}", s.id, to_string(s.state), s.failure ? ": " + log_safe(s.failure->detail) : "");
  };
  JobManager jobs(jc);

  ConnectionLimits limits;
  limits.threads = config.http_threads;
  limits.max_queued = config.http_queue;
  limits.max_connections = config.max_connections;
  limits.max_streams = config.max_event_streams;
  limits.header_timeout = std::chrono::seconds(config.header_timeout);
  limits.body_grace = std::chrono::seconds(config.body_grace);
  limits.body_min_rate = config.body_min_rate;
  limits.read_timeout = std::chrono::seconds(config.read_timeout);
  limits.write_timeout = std::chrono::seconds(config.write_timeout);
  limits.keep_alive_max_count = 1000;  // batch clients reuse one connection
  ConnectionServer server(limits);
  server.set_stream_requests(is_event_stream_request);
  HttpApi api(config, jobs, metrics, *tenants);
  api.install(server);
  server.set_payload_max_length(config.max_upload_bytes);
  // Small answers must not wait for the peer's delayed ACK (Nagle): it cost
  // 40 ms on every synchronous job.
  server.set_tcp_nodelay(true);

  int port = config.port;
  errno = 0;
  if (port == 0) {
    port = server.bind_to_any_port(config.host);
  } else if (!server.bind_to_port(config.host, port)) {
    port = -1;
  }
  if (port < 0) {
    const int why = errno;
    throw Error(ErrorCode::io_error, "cannot listen on " + config.host + ":" + std::to_string(config.port) +
                                         (why == EADDRINUSE ? ": the port is in use (is another voxd serving it?)"
                                          : why != 0        ? std::string(": ") + std::strerror(why)
                                                            : std::string()));
  }
  server.apply_backlog();

  std::thread stopper([&] {
    int signal = 0;
    while (sigwait(&stop_signals, &signal) == 0 && signal == SIGHUP) tenants->reload();
    log(std::string("received ") + (signal == SIGTERM ? "SIGTERM" : "SIGINT") + ": draining");
    api.set_draining();
    jobs.shutdown(std::chrono::seconds(config.shutdown_grace));
    server.stop();
  });
  for (const GpuInfo& gpu : cuda_devices())
    log("GPU " + gpu.name + " (" + std::to_string(gpu.memory_bytes >> 20) + " MiB, compute " +
        std::to_string(gpu.compute_major) + "." + std::to_string(gpu.compute_minor) + ")");
  log(std::string("device ") + to_string(config.device) +
      (cuda_devices().empty() ? " (no GPU: " + cuda_unavailable_reason() + ")" : ""));
  log("listening on http://" + config.host + ":" + std::to_string(port) + " (data dir " + config.data_dir + ")");
  server.listen_after_bind();
  // listen_after_bind returns after stop(); a failure to serve without a
  // signal still has to end the stopper thread.
  if (server.is_running() || stopper.joinable()) {
    pthread_kill(stopper.native_handle(), SIGTERM);
    stopper.join();
  }
  server.close_connections();
  log("stopped");
  return 0;
}

}  // namespace voxd::cli
