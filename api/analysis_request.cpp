#include "api/analysis_request.h"
#include "api/slice_options.h"

#include <openssl/evp.h>

#include <stdexcept>

#include "api/analyses/analysis_kind.h"
#include "api/param_error.h"
#include "voxd/encode/number_text.h"

namespace voxd::api {
namespace {

using nlohmann::json;

// Each one costs worker time and disk; a client that wants more asks the
// routes afterwards.
constexpr std::size_t kMaxAnalyses = 64;

}  // namespace

AnalysisRequest parse_analysis_request(AnalysisKind kind, const Fields& given, const std::string& path_prefix) {
  // A '+' left unescaped in a URL query arrives as a space: "+z" as " z".
  Fields fields = given;
  for (auto& [k, v] : fields)
    if (k == "view" && v.size() == 2 && v[0] == ' ') v[0] = '+';
  FieldReader in(fields, path_prefix);
  AnalysisRequest r;
  r.kind = kind;
  analysis_kind_request(kind).parse(in, r);
  in.finish();
  return r;
}

std::string AnalysisRequest::peel_query() const {
  // Only when peeling, so the plain requests keep their short URLs.
  return peel > 0 ? "&peel=" + std::to_string(peel) + "&peel_metric=" + to_string(peel_metric) : std::string();
}

std::string AnalysisRequest::query() const { return analysis_kind_request(kind).query(*this); }

bool AnalysisRequest::slice_coloured() const { return colour == kSliceName; }

std::string AnalysisRequest::slice_query() const {
  if (!slice_coloured()) return "";
  std::string out = "&slice=";
  static const char* const kHex = "0123456789ABCDEF";
  for (const unsigned char c : slice_json) {
    if ((c >= '0' && c <= '9') || (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '-' || c == '.' || c == '_' ||
        c == '~') {
      out += static_cast<char>(c);
    } else {
      out += '%';
      out += kHex[c >> 4];
      out += kHex[c & 15];
    }
  }
  return out;
}

namespace {

// Lowercase hex SHA-256 of `text`.
std::string sha256_hex(const std::string& text) {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  if (EVP_Digest(text.data(), text.size(), digest, &length, EVP_sha256(), nullptr) != 1)
    throw std::runtime_error("SHA-256 failed");
  static const char* const kHex = "0123456789abcdef";
  std::string out;
  for (unsigned int i = 0; i < length; ++i) {
    out += kHex[digest[i] >> 4];
    out += kHex[digest[i] & 15];
  }
  return out;
}

}  // namespace

std::string AnalysisRequest::artifact_key() const {
  // File-name safe: the query with its separators and signs spelled out; a
  // slice function's JSON (any length, any characters) by its digest.
  std::string q = query();
  std::string suffix;
  if (!slice_json.empty() && slice_coloured()) {
    q.erase(q.size() - slice_query().size());
    suffix = "__slice-" + sha256_hex(slice_json).substr(0, 40);
  }
  std::string key = std::string(to_string(kind)) + "_";
  for (char c : q) {
    if (c == '&') key += "__";
    else if (c == '=') key += "-";
    else if (c == '%') key += "p";
    else if (c == '.' || c == '_' || (c >= '0' && c <= '9') || (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z')) key += c;
    else if (c == '-') key += "m";
    else key += "x";
  }
  return key + suffix;
}

const char* AnalysisRequest::content_type() const { return analysis_kind_request(kind).content_type(*this); }

std::vector<AnalysisRequest> parse_analyses(const json& analyses) {
  std::vector<FieldError> errors;
  std::vector<AnalysisRequest> out;
  if (!analyses.is_array())
    throw InvalidParams(std::vector<FieldError>{
        {"/analyses", "must be an array of analysis objects, got " + std::string(analyses.type_name())}});
  if (analyses.size() > kMaxAnalyses)
    throw InvalidParams(std::vector<FieldError>{{"/analyses", "at most " + std::to_string(kMaxAnalyses) + " analyses per job"}});
  for (std::size_t i = 0; i < analyses.size(); ++i) {
    const std::string path = "/analyses/" + std::to_string(i);
    const json& a = analyses[i];
    if (!a.is_object()) {
      errors.push_back({path, "must be an object with a \"kind\", got " + std::string(a.type_name())});
      continue;
    }
    std::optional<AnalysisKind> kind;
    if (!a.contains("kind") || !a.at("kind").is_string() || !(kind = value_named(kAnalysisKindNames, a.at("kind").get<std::string>()))) {
      errors.push_back({path + "/kind", "must be one of " + names_joined(kAnalysisKindNames, ", ", ", ")});
      continue;
    }
    Fields fields;
    bool typed = true;
    for (const auto& [k, v] : a.items()) {
      if (k == "kind") continue;
      if (v.is_string()) fields.emplace_back(k, v.get<std::string>());
      else if (k == kSliceName && v.is_object()) fields.emplace_back(k, v.dump());  // a slice function, as a slice job's
      else if (v.is_boolean()) fields.emplace_back(k, v.get<bool>() ? "true" : "false");
      else if (v.is_number_integer()) fields.emplace_back(k, v.dump());
      else if (v.is_number()) fields.emplace_back(k, number_text(v.get<double>()));
      else {
        errors.push_back({path + "/" + k, "must be a string, number or boolean (\"slice\": an object), got " + std::string(v.type_name())});
        typed = false;
      }
    }
    if (!typed) continue;
    try {
      out.push_back(parse_analysis_request(*kind, fields, path));
    } catch (const InvalidParams& e) {
      errors.insert(errors.end(), e.errors().begin(), e.errors().end());
    }
  }
  if (!errors.empty()) throw InvalidParams(std::move(errors));
  return out;
}

nlohmann::json to_json(const AnalysisRequest& r) {
  json j{{"kind", to_string(r.kind)}};
  analysis_kind_request(r.kind).add_json(r, j);
  return j;
}

}  // namespace voxd::api
