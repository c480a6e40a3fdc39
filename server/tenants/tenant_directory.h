#pragma once
// Who may use the service, as which tenant, within which quotas: the key file
// of `voxd serve --tenants FILE` (docs/security.md), and the --api-keys of
// a service without one. Keys are kept as their SHA-256 only, looked up in
// constant time per candidate, and never logged. The file is read again
// when it changes (checked at most every 2 s, on a request) and on SIGHUP;
// a file that no longer parses keeps the last good one and logs why.
//
//   {"tenants": [{"name": "acme", "keys": ["sha256:<64 hex>"], "admin": false,
//                 "quotas": {"concurrent_jobs": 4, "queued_jobs": 16,
//                            "stored_bytes": 10737418240, "requests_per_minute": 600},
//                 "webhook_secret": "…"}],
//    "webhook_hosts": ["hooks.example.com", "127.0.0.1:9000"]}
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace voxd::server {

// 0 means no limit.
struct TenantQuotas {
  std::uint64_t concurrent_jobs = 0;  // its jobs not finished (queued or running)
  std::uint64_t queued_jobs = 0;      // its jobs waiting for a worker
  std::uint64_t stored_bytes = 0;     // bytes its succeeded jobs' results take
  std::uint64_t requests_per_minute = 0;  // /v1 requests, per replica
};

struct Tenant {
  std::string name;  // [A-Za-z0-9._-], 1..64; "" is the unnamed tenant of --api-keys and of no keys
  bool admin = false;  // sees and manages every tenant's jobs
  TenantQuotas quotas;
  std::string webhook_secret;  // signs its jobs' callbacks; empty: none may name one
};

// What the file says, parsed and checked.
struct TenantTable {
  std::vector<Tenant> tenants;
  std::vector<std::pair<std::string, std::size_t>> keys;  // SHA-256 hex -> index in tenants
  std::vector<std::string> webhook_hosts;                 // "host" or "host:port", lowercase
};

// Parses a key file's text; throws std::invalid_argument saying what is
// wrong (never quoting a key).
TenantTable parse_tenant_table(std::string_view text);

// Lowercase hex SHA-256 of a key, as the file stores it after "sha256:".
std::string key_digest(std::string_view key);

class TenantDirectory {
 public:
  // `file` empty: the tenants are `api_keys` (the unnamed tenant) or, with
  // none, nobody needs a key. `webhook_hosts` and `webhook_secret` (from
  // flags) are the unnamed tenant's; a file's own apply to its tenants.
  // Throws std::invalid_argument when the file cannot be read or parsed.
  TenantDirectory(std::filesystem::path file, const std::vector<std::string>& api_keys,
                  std::vector<std::string> webhook_hosts, std::string webhook_secret);

  // Whether requests need a key at all.
  bool needs_key();
  // The tenant a bearer key names, or nothing.
  std::optional<Tenant> authenticate(std::string_view key);
  // The tenant named so now (its secret for a callback); nothing when it
  // was removed from the file.
  std::optional<Tenant> find(const std::string& name);
  // Every named tenant's name, for metrics labels: only these are ever labels.
  std::vector<std::string> names();
  // The unnamed tenant sees every job while no tenant has a name (the
  // service without a tenants file, as before tenants existed).
  bool unnamed_sees_all();
  // Whether a callback may go to `host` on `port`: an entry "host:port"
  // allows that port, a bare "host" the web's ports 80 and 443. Hosts
  // compare case-insensitively, as names: no lookup, so an entry allows
  // exactly what it says.
  bool webhook_host_allowed(const std::string& host, int port);

  // Reads the file again now (SIGHUP). False, with the reason logged, when
  // it could not be read or parsed: the last good table stays.
  bool reload();

 private:
  std::shared_ptr<const TenantTable> table();  // reloaded first when the file changed
  std::shared_ptr<const TenantTable> read_file();  // under mutex_ once constructed
  TenantTable with_flags(TenantTable table) const;

  const std::filesystem::path file_;
  const std::vector<std::string> api_keys_;
  std::vector<std::string> flag_hosts_;
  const std::string flag_secret_;
  std::mutex mutex_;
  std::shared_ptr<const TenantTable> table_;
  std::filesystem::file_time_type mtime_{};
  std::uintmax_t size_ = 0;
  std::chrono::steady_clock::time_point checked_{};
};

}  // namespace voxd::server
