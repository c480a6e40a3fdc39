#include "server/cli/cli_serve_config.h"

#include <cstdlib>
#include <functional>
#include <sstream>

#include "server/cli/cli_args.h"
#include "voxd/encode/number_text.h"

#include "server/redis/redis_client.h"

namespace voxd::cli {
namespace {

using server::ServeConfig;
using server::parse_redis_url;

struct Option {
  const char* flag;
  const char* help;
  std::function<void(ServeConfig&, const std::string&, const std::string&)> set;  // (config, value, source)
  std::function<std::string(const ServeConfig&)> show;
};

std::uint64_t to_u64(const std::string& v, const std::string& source, std::uint64_t lo, std::uint64_t hi) {
  if (const auto n = parse_number<std::uint64_t>(v); n && *n >= lo && *n <= hi) return *n;
  throw UsageError(source + " expects an integer between " + std::to_string(lo) + " and " + std::to_string(hi) +
                   ", got '" + v + "'");
}

std::vector<std::string> to_list(const std::string& v) {
  std::vector<std::string> out;
  std::stringstream ss(v);
  std::string item;
  while (std::getline(ss, item, ','))
    if (!item.empty()) out.push_back(item);
  return out;
}

std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ",") + x;
  return s;
}

const std::vector<Option>& options() {
  static const std::vector<Option> opts = {
      {"host", "address to listen on", [](ServeConfig& c, const std::string& v, const std::string&) { c.host = v; },
       [](const ServeConfig& c) { return c.host; }},
      {"port", "TCP port; 0 picks a free one",
       [](ServeConfig& c, const std::string& v, const std::string& s) { c.port = static_cast<int>(to_u64(v, s, 0, 65535)); },
       [](const ServeConfig& c) { return std::to_string(c.port); }},
      {"workers", "voxelization worker threads; 0 = one per core",
       [](ServeConfig& c, const std::string& v, const std::string& s) { c.workers = static_cast<int>(to_u64(v, s, 0, 1024)); },
       [](const ServeConfig& c) { return std::to_string(c.workers); }},
      {"device", "where jobs that name no \"device\" run what a GPU can (a slice job's colours): auto (a GPU where there is one and the job pays for it), cpu, or cuda (needs a GPU; checked at start)",
       [](ServeConfig& c, const std::string& v, const std::string& s) {
         const std::optional<ComputeDevice> d = compute_device_from_string(v);
         if (!d) throw UsageError(s + " must be auto, cpu or cuda, got '" + v + "'");
         if (*d == ComputeDevice::cuda && !cuda_unavailable_reason().empty())
           throw UsageError(s + ": " + cuda_unavailable_reason());
         c.device = *d;
       },
       [](const ServeConfig& c) { return std::string(to_string(c.device)); }},
      {"queue-size", "jobs waiting for a worker before 429",
       [](ServeConfig& c, const std::string& v, const std::string& s) { c.queue_size = to_u64(v, s, 1, 1000000); },
       [](const ServeConfig& c) { return std::to_string(c.queue_size); }},
      {"data-dir", "job records and results", [](ServeConfig& c, const std::string& v, const std::string&) { c.data_dir = v; },
       [](const ServeConfig& c) { return c.data_dir; }},
      {"max-upload-bytes", "largest request body (413 above)",
       [](ServeConfig& c, const std::string& v, const std::string& s) { c.max_upload_bytes = to_u64(v, s, 1, std::uint64_t{1} << 40); },
       [](const ServeConfig& c) { return std::to_string(c.max_upload_bytes); }},
      {"max-triangles", "largest mesh (422 above)",
       [](ServeConfig& c, const std::string& v, const std::string& s) { c.max_triangles = to_u64(v, s, 1, std::uint64_t{1} << 32); },
       [](const ServeConfig& c) { return std::to_string(c.max_triangles); }},
      {"max-voxels", "largest grid made whole in memory (422 above; a job that can stream streams instead)",
       [](ServeConfig& c, const std::string& v, const std::string& s) { c.max_voxels = to_u64(v, s, 1, std::uint64_t{1} << 40); },
       [](const ServeConfig& c) { return std::to_string(c.max_voxels); }},
      {"max-streamed-voxels", "largest grid made slab by slab into its stored RLE (422 above): disk and time bound it, not memory",
       [](ServeConfig& c, const std::string& v, const std::string& s) { c.max_streamed_voxels = to_u64(v, s, 1, std::uint64_t{1} << 48); },
       [](const ServeConfig& c) { return std::to_string(c.max_streamed_voxels); }},
      {"max-job-memory", "bytes of volumes one job, or one analysis of it, may need (422 above); jobs past it stream where they can",
       [](ServeConfig& c, const std::string& v, const std::string& s) { c.max_job_memory = to_u64(v, s, 1, std::uint64_t{1} << 44); },
       [](const ServeConfig& c) { return std::to_string(c.max_job_memory); }},
      {"max-decode-memory", "bytes the isolated Draco decoder process may allocate (422 above)",
       [](ServeConfig& c, const std::string& v, const std::string& s) { c.max_decode_memory = to_u64(v, s, std::uint64_t{16} << 20, std::uint64_t{1} << 44); },
       [](const ServeConfig& c) { return std::to_string(c.max_decode_memory); }},
      {"memory-budget", "bytes all queued and running jobs, decodes and analyses may take at once (429 above); 0 = 60% of the machine's or container's memory",
       [](ServeConfig& c, const std::string& v, const std::string& s) { c.memory_budget = to_u64(v, s, 0, std::uint64_t{1} << 48); },
       [](const ServeConfig& c) { return std::to_string(c.memory_budget); }},
      {"min-free-disk", "bytes the data directory's disk keeps free: below, submissions get 507 and /readyz is not ready",
       [](ServeConfig& c, const std::string& v, const std::string& s) { c.min_free_disk = to_u64(v, s, 0, std::uint64_t{1} << 50); },
       [](const ServeConfig& c) { return std::to_string(c.min_free_disk); }},
      {"result-ttl", "seconds finished jobs are kept",
       [](ServeConfig& c, const std::string& v, const std::string& s) { c.result_ttl = to_u64(v, s, 1, std::uint64_t{1} << 32); },
       [](const ServeConfig& c) { return std::to_string(c.result_ttl); }},
      {"sync-max-voxels", "largest grid POST /v1/voxelize accepts",
       [](ServeConfig& c, const std::string& v, const std::string& s) { c.sync_max_voxels = to_u64(v, s, 1, std::uint64_t{1} << 40); },
       [](const ServeConfig& c) { return std::to_string(c.sync_max_voxels); }},
      {"http-threads", "threads serving HTTP requests",
       [](ServeConfig& c, const std::string& v, const std::string& s) { c.http_threads = static_cast<int>(to_u64(v, s, 1, 1024)); },
       [](const ServeConfig& c) { return std::to_string(c.http_threads); }},
      {"http-queue", "requests waiting for an HTTP thread before 429",
       [](ServeConfig& c, const std::string& v, const std::string& s) { c.http_queue = to_u64(v, s, 1, 1000000); },
       [](const ServeConfig& c) { return std::to_string(c.http_queue); }},
      {"max-connections", "open connections before 503 (slow or idle clients included)",
       [](ServeConfig& c, const std::string& v, const std::string& s) { c.max_connections = to_u64(v, s, 1, 1000000); },
       [](const ServeConfig& c) { return std::to_string(c.max_connections); }},
      {"max-event-streams", "event streams (GET /v1/jobs/{id}/events) open at once, each on a thread beside the HTTP threads (503 above)",
       [](ServeConfig& c, const std::string& v, const std::string& s) { c.max_event_streams = to_u64(v, s, 1, 100000); },
       [](const ServeConfig& c) { return std::to_string(c.max_event_streams); }},
      {"header-timeout", "seconds from a request's first byte to the end of its head (408 after)",
       [](ServeConfig& c, const std::string& v, const std::string& s) { c.header_timeout = static_cast<int>(to_u64(v, s, 1, 3600)); },
       [](const ServeConfig& c) { return std::to_string(c.header_timeout); }},
      {"body-grace", "seconds any request body may take, plus its size at --body-min-rate",
       [](ServeConfig& c, const std::string& v, const std::string& s) { c.body_grace = static_cast<int>(to_u64(v, s, 1, 3600)); },
       [](const ServeConfig& c) { return std::to_string(c.body_grace); }},
      {"body-min-rate", "bytes a second a request body must average after its grace",
       [](ServeConfig& c, const std::string& v, const std::string& s) { c.body_min_rate = to_u64(v, s, 1, std::uint64_t{1} << 40); },
       [](const ServeConfig& c) { return std::to_string(c.body_min_rate); }},
      {"read-timeout", "seconds a request may stall while being read",
       [](ServeConfig& c, const std::string& v, const std::string& s) { c.read_timeout = static_cast<int>(to_u64(v, s, 1, 3600)); },
       [](const ServeConfig& c) { return std::to_string(c.read_timeout); }},
      {"write-timeout", "seconds a response may stall while being written",
       [](ServeConfig& c, const std::string& v, const std::string& s) { c.write_timeout = static_cast<int>(to_u64(v, s, 1, 3600)); },
       [](const ServeConfig& c) { return std::to_string(c.write_timeout); }},
      {"cors-origins", "comma-separated origins allowed by CORS (* = any)",
       [](ServeConfig& c, const std::string& v, const std::string&) { c.cors_origins = to_list(v); },
       [](const ServeConfig& c) { return join(c.cors_origins); }},
      {"api-keys", "comma-separated bearer keys required on /v1 routes",
       [](ServeConfig& c, const std::string& v, const std::string&) { c.api_keys = to_list(v); },
       [](const ServeConfig& c) { return c.api_keys.empty() ? std::string() : std::string("(set)"); }},
      {"tenants", "JSON key file: tenants, their hashed keys, quotas, admin role and webhook secrets, and the webhook allow-list "
                  "(docs/security.md); read again when it changes and on SIGHUP",
       [](ServeConfig& c, const std::string& v, const std::string&) { c.tenants_file = v; },
       [](const ServeConfig& c) { return c.tenants_file; }},
      {"webhook-hosts", "comma-separated host or host:port that job callbacks may go to (beside the tenants file's)",
       [](ServeConfig& c, const std::string& v, const std::string&) { c.webhook_hosts = to_list(v); },
       [](const ServeConfig& c) { return join(c.webhook_hosts); }},
      {"webhook-secret", "signs the callbacks of jobs submitted without a tenant (--api-keys or no keys); 16 characters at least",
       [](ServeConfig& c, const std::string& v, const std::string& s) {
         if (!v.empty() && v.size() < 16) throw UsageError(s + " must be at least 16 characters");
         c.webhook_secret = v;
       },
       [](const ServeConfig& c) { return c.webhook_secret.empty() ? std::string() : std::string("(set)"); }},
      {"log-format", "text or json",
       [](ServeConfig& c, const std::string& v, const std::string& s) {
         if (v != "text" && v != "json") throw UsageError(s + " must be text or json, got '" + v + "'");
         c.log_format = v;
       },
       [](const ServeConfig& c) { return c.log_format; }},
      {"redis", "redis://[:password@]host:port[/db] or unix:///path: share queue, records and results with every replica on this Redis (empty: embedded, one process)",
       [](ServeConfig& c, const std::string& v, const std::string& s) {
         if (!v.empty()) {
           try {
             parse_redis_url(v);
           } catch (const std::invalid_argument& e) {
             throw UsageError(s + ": " + e.what());
           }
         }
         c.redis_url = v;
       },
       [](const ServeConfig& c) { return c.redis_url.empty() ? std::string() : parse_redis_url(c.redis_url).redacted(); }},
      {"redis-lease", "seconds a replica's lease on a running job lasts unrenewed: a job whose replica died runs again elsewhere after it",
       [](ServeConfig& c, const std::string& v, const std::string& s) { c.redis_lease = static_cast<int>(to_u64(v, s, 1, 3600)); },
       [](const ServeConfig& c) { return std::to_string(c.redis_lease); }},
      {"max-deliveries", "times a shared job is handed to a worker before it fails (redelivery-limit)",
       [](ServeConfig& c, const std::string& v, const std::string& s) { c.max_deliveries = static_cast<int>(to_u64(v, s, 1, 100)); },
       [](const ServeConfig& c) { return std::to_string(c.max_deliveries); }},
      {"max-result-bytes", "bytes a job's volumes may take uncompressed with --redis (422 at admission above); 0 = no cap",
       [](ServeConfig& c, const std::string& v, const std::string& s) { c.max_result_bytes = to_u64(v, s, 0, std::uint64_t{1} << 50); },
       [](const ServeConfig& c) { return std::to_string(c.max_result_bytes); }},
      {"slab-task-bytes", "with --redis, a streamed job of bits is split into slab tasks of about this many bytes of bits, made by every replica's workers; 0 = never split",
       [](ServeConfig& c, const std::string& v, const std::string& s) { c.slab_task_bytes = to_u64(v, s, 0, std::uint64_t{1} << 50); },
       [](const ServeConfig& c) { return std::to_string(c.slab_task_bytes); }},
      {"shutdown-grace", "seconds running jobs get to finish on SIGTERM",
       [](ServeConfig& c, const std::string& v, const std::string& s) { c.shutdown_grace = static_cast<int>(to_u64(v, s, 0, 3600)); },
       [](const ServeConfig& c) { return std::to_string(c.shutdown_grace); }},
  };
  return opts;
}

std::string env_name(const std::string& flag) {
  // The one variable named for what it holds rather than for its flag.
  if (flag == "redis") return "VOXD_REDIS_URL";
  std::string n = "VOXD_";
  for (char ch : flag) n += ch == '-' ? '_' : static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
  return n;
}

}  // namespace

ServeConfig parse_serve_config(int argc, char** argv, int first) {
  ServeConfig config;
  std::set<std::string> valued;
  for (const auto& o : options()) valued.insert(o.flag);
  cli::Args args(argc, argv, first, valued, {"help"});
  if (!args.positional().empty()) throw UsageError("serve takes no positional arguments (see voxd serve --help)");
  for (const auto& o : options()) {
    const std::string env = env_name(o.flag);
    if (const char* v = std::getenv(env.c_str())) o.set(config, v, env);
    if (auto v = args.value(o.flag)) o.set(config, *v, std::string("--") + o.flag);
  }
  return config;
}

std::string serve_help() {
  std::ostringstream s;
  s << "usage: voxd serve [options]\n\nRuns the HTTP service. Every option can also be set in the environment\n"
       "as VOXD_<NAME> (e.g. VOXD_PORT=9000); flags win.\n\n";
  const ServeConfig defaults;
  for (const auto& o : options()) {
    std::string left = std::string("  --") + o.flag + " (" + env_name(o.flag) + ")";
    if (left.size() < 44) left.resize(44, ' ');
    const std::string def = o.show(defaults);
    s << left << ' ' << o.help << (def.empty() ? "" : " [default: " + def + "]") << '\n';
  }
  s << "\nGrids past memory. A solid, surface or solid+surface job with the parity inside\n"
       "test, and a coverage job, stream (job parameter \"streaming\": auto, on or off;\n"
       "auto past 512 MiB of volumes or past --max-job-memory): they are voxelized slab\n"
       "by slab into their stored RLE and take the memory of one slab, whatever the grid.\n"
       "  Stream over any grid: GET /volume as rle, raw or nrrd; radiography (without\n"
       "  peel); sections (without peel or colour=thickness); shaded previews (without\n"
       "  colour=thickness); analysis with thickness=false&skin=false (mass properties,\n"
       "  parts, voids).\n"
       "  Need the whole grid (run while it fits --max-job-memory, else 422 naming the\n"
       "  largest grid they accept): volume as binvox, local thickness, analysis with\n"
       "  thickness, skin or clean-up, peeled models, thickness colours.\n";
  return s.str();
}

}  // namespace voxd::cli
