#pragma once
// `voxd serve` settings, with embedded defaults so the service starts with
// no configuration at all; read from flags and the environment by the CLI
// (server/cli/cli_serve_config.h).
#include <cstdint>
#include <string>
#include <vector>

#include "voxd/compute_device.h"

namespace voxd::server {

struct ServeConfig {
  std::string host = "127.0.0.1";
  int port = 8080;  // 0: any free port (the chosen one is logged)
  int workers = 0;  // 0: one per core
  // Where jobs that name no "device" run what a GPU can (a slice job's colours).
  ComputeDevice device = ComputeDevice::automatic;
  std::size_t queue_size = 64;
  std::string data_dir = "voxd-data";
  std::uint64_t max_upload_bytes = std::uint64_t{256} << 20;
  std::uint64_t max_triangles = 20'000'000;
  std::uint64_t max_voxels = std::uint64_t{1} << 33;
  std::uint64_t max_streamed_voxels = std::uint64_t{1} << 40;  // a grid made slab by slab
  std::uint64_t max_job_memory = std::uint64_t{4} << 30;
  std::uint64_t max_decode_memory = std::uint64_t{2} << 30;  // the isolated Draco decoder's data segment
  std::uint64_t memory_budget = 0;  // all jobs, decodes and analyses at once; 0 = 60% of memory
  std::uint64_t min_free_disk = std::uint64_t{64} << 20;  // 507 and not ready below
  std::uint64_t result_ttl = 86400;       // seconds
  std::uint64_t sync_max_voxels = 1 << 24;  // POST /v1/voxelize
  int http_threads = 16;
  std::size_t http_queue = 256;      // requests waiting for an HTTP thread (429 above)
  std::size_t max_connections = 1024;  // open connections (503 above)
  std::size_t max_event_streams = 64;  // open event streams, each on a thread of its own (503 above)
  int header_timeout = 10;  // seconds from a request's first byte to the end of its head
  int body_grace = 10;                      // seconds any request body may take...
  std::uint64_t body_min_rate = 16 * 1024;  // ...plus its size at this many bytes/s
  int read_timeout = 30;   // seconds without progress before a request is dropped
  int write_timeout = 30;
  std::vector<std::string> cors_origins;  // "*" allows any
  std::vector<std::string> api_keys;      // empty: no authentication (unless a tenants file)
  std::string tenants_file;               // server/tenants/tenant_directory.h; empty: none
  std::vector<std::string> webhook_hosts;  // callbacks may go to these (beside the file's)
  std::string webhook_secret;             // the unnamed tenant's callbacks' signing secret
  std::string log_format = "text";        // text | json
  int shutdown_grace = 30;                // seconds running jobs get on SIGTERM
  // Scale-out: replicas sharing one Redis (docs/scale-out.md). Empty: embedded.
  std::string redis_url;
  int redis_lease = 15;  // seconds
  int max_deliveries = 3;
  std::uint64_t max_result_bytes = std::uint64_t{1} << 30;  // with --redis only
  std::uint64_t slab_task_bytes = std::uint64_t{1} << 30;  // with --redis only
};

}  // namespace voxd::server
