#include "server/http/job_labels.h"

#include <algorithm>

#include <nlohmann/json.hpp>

#include "api/param_error.h"
#include "server/webhooks/webhook_url.h"

namespace voxd::server {
namespace {

bool tag_key_ok(const std::string& k) {
  return !k.empty() && k.size() <= 64 && std::all_of(k.begin(), k.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-';
  });
}

// Printable text: no control characters (a name ends up in logs, lists and
// the page), valid UTF-8 as JSON needs.
bool printable(const std::string& s) {
  if (std::any_of(s.begin(), s.end(), [](char c) { return static_cast<unsigned char>(c) < 0x20 || c == 0x7f; })) return false;
  try {
    (void)nlohmann::json(s).dump();
    return true;
  } catch (const nlohmann::json::exception&) {
    return false;
  }
}

[[noreturn]] void refuse(const std::string& path, const std::string& message) {
  throw api::InvalidParams(std::vector<api::FieldError>{{path, message}});
}

// A file name as the client's path may send it ("C:\\parts\\a.stl"): its last part.
std::string base_name(const std::string& filename) {
  const std::size_t slash = filename.find_last_of("/\\");
  return slash == std::string::npos ? filename : filename.substr(slash + 1);
}

}  // namespace

JobLabels job_labels_of(const Submission& s, const Caller& caller, TenantDirectory& tenants) {
  JobLabels labels;
  labels.tenant = caller.tenant.name;
  if (s.name) {
    if (s.name->size() > kMaxJobNameBytes || !printable(*s.name))
      refuse("/name", "the job's name must be printable text of at most " + std::to_string(kMaxJobNameBytes) + " bytes");
    labels.name = *s.name;
  } else {
    // The uploaded file's name, as the page and lists show it; cut, never refused.
    labels.name = base_name(s.filename);
    if (labels.name.size() > kMaxJobNameBytes || !printable(labels.name)) labels.name.clear();
  }
  if (s.tags && !s.tags->empty()) {
    const nlohmann::json tags = nlohmann::json::parse(*s.tags, nullptr, /*allow_exceptions=*/false);
    if (!tags.is_object())
      refuse("/tags", "tags must be a JSON object of strings, e.g. {\"project\": \"pump\", \"rev\": \"b\"}");
    if (tags.size() > kMaxJobTags) refuse("/tags", "a job has at most " + std::to_string(kMaxJobTags) + " tags");
    for (const auto& [key, value] : tags.items()) {
      if (!tag_key_ok(key)) refuse("/tags", "a tag's key must be 1 to 64 of A-Z a-z 0-9 . _ - (got a key of " + std::to_string(key.size()) + " bytes)");
      if (!value.is_string() || value.get<std::string>().size() > 256 || !printable(value.get<std::string>()))
        refuse("/tags/" + key, "a tag's value must be printable text of at most 256 bytes");
      labels.tags.emplace_back(key, value.get<std::string>());
    }
  }
  if (s.callback && !s.callback->empty()) {
    std::string why;
    const std::optional<WebhookUrl> url = parse_webhook_url(*s.callback, &why);
    if (!url) refuse("/callback", "the callback URL is refused: " + why);
    if (!tenants.webhook_host_allowed(url->host, url->port))
      refuse("/callback", "the callback's host " + url->host + ":" + std::to_string(url->port) +
                              " is not in this service's webhook allow-list (webhook_hosts); ask its operator to add it");
    if (caller.tenant.webhook_secret.empty())
      refuse("/callback", "this service has no webhook secret for your tenant, so it cannot sign callbacks; ask its operator to set one");
    labels.callback = *s.callback;
  }
  return labels;
}

JobFilter job_filter_of(const httplib::Request& req, const Caller& caller) {
  JobFilter filter = caller.jobs();
  filter.name = req.get_param_value("name");
  const std::size_t n = req.get_param_value_count("tag");
  for (std::size_t i = 0; i < n; ++i) {
    const std::string tag = req.get_param_value("tag", i);
    const std::size_t colon = tag.find(':');
    if (colon == std::string::npos || !tag_key_ok(tag.substr(0, colon)))
      throw ProblemError(make_problem(400, "invalid-query", "Invalid query parameter",
                                      "tag must be key:value with a key of A-Z a-z 0-9 . _ -, got '" + tag + "'"));
    filter.tags.emplace_back(tag.substr(0, colon), tag.substr(colon + 1));
  }
  return filter;
}

}  // namespace voxd::server
