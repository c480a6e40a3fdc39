#include "server/tenants/tenant_directory.h"

#include <openssl/evp.h>

#include <algorithm>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

namespace voxd::server {
namespace {

using nlohmann::json;

constexpr std::chrono::seconds kRecheck{2};

bool valid_tenant_name(const std::string& name) {
  if (name.empty() || name.size() > 64) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' || c == '_' || c == '-';
  });
}

bool lower_hex(const std::string& s) {
  return std::all_of(s.begin(), s.end(), [](char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'); });
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c);
  return s;
}

bool equal_digests(const std::string& a, const std::string& b) {
  if (a.size() != b.size()) return false;
  unsigned char diff = 0;
  for (std::size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ b[i]);
  return diff == 0;
}

std::uint64_t quota(const json& quotas, const char* name, const std::string& where) {
  if (!quotas.contains(name)) return 0;
  const json& v = quotas.at(name);
  if (!v.is_number_unsigned()) throw std::invalid_argument(where + ": quotas." + name + " must be a whole number >= 0 (0: no limit)");
  return v.get<std::uint64_t>();
}

void add_unnamed(TenantTable& table, const std::vector<std::string>& api_keys, const std::string& secret) {
  if (api_keys.empty()) return;
  Tenant t;
  t.webhook_secret = secret;
  table.tenants.push_back(t);
  for (const std::string& key : api_keys) table.keys.emplace_back(key_digest(key), table.tenants.size() - 1);
}

}  // namespace

std::string key_digest(std::string_view key) {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int n = 0;
  if (EVP_Digest(key.data(), key.size(), digest, &n, EVP_sha256(), nullptr) != 1) throw std::runtime_error("SHA-256 failed");
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  for (unsigned int i = 0; i < n; ++i) {
    out += kHex[digest[i] >> 4];
    out += kHex[digest[i] & 15];
  }
  return out;
}

TenantTable parse_tenant_table(std::string_view text) {
  json doc;
  try {
    doc = json::parse(text);
  } catch (const json::exception& e) {  // parse_error, and out_of_range for a number like 1e400
    throw std::invalid_argument(std::string("not JSON: ") + e.what());
  }
  if (!doc.is_object() || !doc.contains("tenants") || !doc.at("tenants").is_array())
    throw std::invalid_argument("the file must be an object with an array \"tenants\"");
  for (const auto& [field, value] : doc.items())
    if (field != "tenants" && field != "webhook_hosts") throw std::invalid_argument("unknown field \"" + field + "\"");
  TenantTable table;
  for (const json& t : doc.at("tenants")) {
    const std::string where = "tenant " + std::to_string(table.tenants.size() + 1);
    if (!t.is_object()) throw std::invalid_argument(where + " is not an object");
    for (const auto& [field, value] : t.items())
      if (field != "name" && field != "keys" && field != "admin" && field != "quotas" && field != "webhook_secret")
        throw std::invalid_argument(where + ": unknown field \"" + field + "\"");
    Tenant tenant;
    if (!t.contains("name") || !t.at("name").is_string() || !valid_tenant_name(t.at("name").get<std::string>()))
      throw std::invalid_argument(where + ": \"name\" must be 1 to 64 of A-Z a-z 0-9 . _ -");
    tenant.name = t.at("name");
    for (const Tenant& other : table.tenants)
      if (other.name == tenant.name) throw std::invalid_argument("tenant \"" + tenant.name + "\" is named twice");
    const std::string named = "tenant \"" + tenant.name + "\"";
    if (t.contains("admin")) {
      if (!t.at("admin").is_boolean()) throw std::invalid_argument(named + ": \"admin\" must be true or false");
      tenant.admin = t.at("admin");
    }
    if (t.contains("quotas")) {
      const json& q = t.at("quotas");
      if (!q.is_object()) throw std::invalid_argument(named + ": \"quotas\" must be an object");
      for (const auto& [field, value] : q.items())
        if (field != "concurrent_jobs" && field != "queued_jobs" && field != "stored_bytes" && field != "requests_per_minute")
          throw std::invalid_argument(named + ": unknown quota \"" + field + "\"");
      tenant.quotas = {quota(q, "concurrent_jobs", named), quota(q, "queued_jobs", named), quota(q, "stored_bytes", named),
                       quota(q, "requests_per_minute", named)};
    }
    if (t.contains("webhook_secret")) {
      if (!t.at("webhook_secret").is_string() || t.at("webhook_secret").get<std::string>().size() < 16)
        throw std::invalid_argument(named + ": \"webhook_secret\" must be a string of at least 16 characters");
      tenant.webhook_secret = t.at("webhook_secret");
    }
    if (!t.contains("keys") || !t.at("keys").is_array())
      throw std::invalid_argument(named + ": \"keys\" must be an array of \"sha256:<64 hex>\"");
    table.tenants.push_back(tenant);
    for (const json& k : t.at("keys")) {
      const std::string text = k.is_string() ? k.get<std::string>() : std::string();
      // Only the digest is ever in the file: a plain key there is refused
      // (without quoting it back).
      if (text.size() != 71 || text.rfind("sha256:", 0) != 0 || !lower_hex(text.substr(7)))
        throw std::invalid_argument(named + ": each key must be \"sha256:\" and the key's SHA-256 in 64 lowercase hex "
                                            "digits (printf %s KEY | sha256sum)");
      const std::string digest = text.substr(7);
      for (const auto& [other, index] : table.keys)
        if (other == digest)
          throw std::invalid_argument(named + ": a key is also \"" + table.tenants[index].name + "\"'s; keys must be unique");
      table.keys.emplace_back(digest, table.tenants.size() - 1);
    }
  }
  if (doc.contains("webhook_hosts")) {
    if (!doc.at("webhook_hosts").is_array()) throw std::invalid_argument("\"webhook_hosts\" must be an array of host or host:port");
    for (const json& h : doc.at("webhook_hosts")) {
      if (!h.is_string() || h.get<std::string>().empty() || h.get<std::string>().find_first_of("/@ ") != std::string::npos)
        throw std::invalid_argument("\"webhook_hosts\" must be an array of host or host:port");
      table.webhook_hosts.push_back(lower(h.get<std::string>()));
    }
  }
  return table;
}

TenantDirectory::TenantDirectory(std::filesystem::path file, const std::vector<std::string>& api_keys,
                                 std::vector<std::string> webhook_hosts, std::string webhook_secret)
    : file_(std::move(file)), api_keys_(api_keys), flag_hosts_(std::move(webhook_hosts)), flag_secret_(std::move(webhook_secret)) {
  for (std::string& h : flag_hosts_) h = lower(h);
  table_ = file_.empty() ? std::make_shared<const TenantTable>(with_flags(TenantTable{})) : read_file();
  checked_ = std::chrono::steady_clock::now();
}

TenantTable TenantDirectory::with_flags(TenantTable table) const {
  add_unnamed(table, api_keys_, flag_secret_);
  if (api_keys_.empty() && !flag_secret_.empty()) table.tenants.push_back(Tenant{"", false, {}, flag_secret_});
  table.webhook_hosts.insert(table.webhook_hosts.end(), flag_hosts_.begin(), flag_hosts_.end());
  return table;
}

std::shared_ptr<const TenantTable> TenantDirectory::read_file() {
  std::error_code ec;
  const auto mtime = std::filesystem::last_write_time(file_, ec);
  const auto size = std::filesystem::file_size(file_, ec);
  std::ifstream in(file_, std::ios::binary);
  if (!in) throw std::invalid_argument("cannot read the tenants file " + file_.string());
  std::stringstream text;
  text << in.rdbuf();
  TenantTable table;
  try {
    table = parse_tenant_table(text.str());
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("the tenants file " + file_.string() + ": " + e.what());
  }
  mtime_ = mtime;
  size_ = size;
  return std::make_shared<const TenantTable>(with_flags(std::move(table)));
}

bool TenantDirectory::reload() {
  if (file_.empty()) return true;
  try {
    std::lock_guard lock(mutex_);
    auto fresh = read_file();
    table_ = std::move(fresh);
    checked_ = std::chrono::steady_clock::now();
    spdlog::info("tenants: read {} ({} tenants)", file_.string(), table_->tenants.size());
    return true;
  } catch (const std::exception& e) {
    spdlog::error("tenants: kept the last good table: {}", e.what());
    return false;
  }
}

std::shared_ptr<const TenantTable> TenantDirectory::table() {
  {
    std::lock_guard lock(mutex_);
    const auto now = std::chrono::steady_clock::now();
    if (file_.empty() || now - checked_ < kRecheck) return table_;
    checked_ = now;
    std::error_code ec;
    const auto mtime = std::filesystem::last_write_time(file_, ec);
    const auto size = std::filesystem::file_size(file_, ec);
    if (!ec && mtime == mtime_ && size == size_) return table_;
  }
  reload();
  std::lock_guard lock(mutex_);
  return table_;
}

bool TenantDirectory::needs_key() {
  const auto t = table();
  return !t->keys.empty() || !file_.empty();
}

std::optional<Tenant> TenantDirectory::authenticate(std::string_view key) {
  const auto t = table();
  const std::string digest = key_digest(key);
  std::optional<std::size_t> found;
  for (const auto& [d, index] : t->keys)
    if (equal_digests(d, digest)) found = index;
  if (!found) return std::nullopt;
  return t->tenants[*found];
}

std::optional<Tenant> TenantDirectory::find(const std::string& name) {
  const auto t = table();
  for (const Tenant& tenant : t->tenants)
    if (tenant.name == name) return tenant;
  return std::nullopt;
}

std::vector<std::string> TenantDirectory::names() {
  const auto t = table();
  std::vector<std::string> out;
  for (const Tenant& tenant : t->tenants)
    if (!tenant.name.empty()) out.push_back(tenant.name);
  return out;
}

bool TenantDirectory::unnamed_sees_all() {
  const auto t = table();
  return std::none_of(t->tenants.begin(), t->tenants.end(), [](const Tenant& x) { return !x.name.empty(); });
}

bool TenantDirectory::webhook_host_allowed(const std::string& host, int port) {
  const auto t = table();
  const std::string h = lower(host);
  const std::string with_port = h + ":" + std::to_string(port);
  for (const std::string& allowed : t->webhook_hosts)
    if (allowed == with_port || (allowed == h && (port == 80 || port == 443))) return true;
  return false;
}

}  // namespace voxd::server
