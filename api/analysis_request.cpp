#include "api/analysis_request.h"

#include <cmath>
#include <initializer_list>

#include "api/param_error.h"
#include "voxd/encode/number_text.h"

namespace voxd::api {
namespace {

using nlohmann::json;

struct FieldReader {
  const Fields& fields;
  std::string prefix;
  std::vector<FieldError> errors;
  std::vector<std::string> used;

  const std::string* find(const std::string& name) {
    const std::string* found = nullptr;
    for (const auto& [k, v] : fields) {
      if (k != name) continue;
      if (found) {
        errors.push_back({prefix + "/" + name, "given more than once"});
        return nullptr;
      }
      found = &v;
    }
    if (found) used.push_back(name);
    return found;
  }

  template <typename E, std::size_t N>
  E choice(const std::string& name, const EnumNames<E, N>& names, E fallback) {
    const std::string* v = find(name);
    if (!v) return fallback;
    if (const auto value = value_named(names, *v)) return *value;
    errors.push_back({prefix + "/" + name, "must be one of " + names_listed(names) + ", got '" + *v + "'"});
    return fallback;
  }

  std::string choice(const std::string& name, std::initializer_list<const char*> allowed, const char* fallback) {
    const std::string* v = find(name);
    if (!v) return fallback;
    std::string list;
    for (const char* a : allowed) {
      if (*v == a) return *v;
      list += list.empty() ? a : std::string(", ") + a;
    }
    errors.push_back({prefix + "/" + name, "must be one of " + list + ", got '" + *v + "'"});
    return fallback;
  }

  // The whole text as a T that satisfies `ok`, or an error saying `wanted`.
  template <typename T, typename Ok>
  std::optional<T> parsed(const std::string& name, Ok ok, const char* wanted) {
    const std::string* v = find(name);
    if (!v) return std::nullopt;
    const std::optional<T> x = parse_number<T>(*v);
    if (!x || !ok(*x)) {
      errors.push_back({prefix + "/" + name, std::string("must be ") + wanted + ", got '" + *v + "'"});
      return std::nullopt;
    }
    return x;
  }
  std::optional<double> positive(const std::string& name) {
    return parsed<double>(name, [](double x) { return std::isfinite(x) && x > 0; }, "a positive length in model units");
  }
  std::optional<double> finite(const std::string& name) {
    return parsed<double>(name, [](double x) { return std::isfinite(x); }, "a number");
  }
  std::optional<std::int64_t> count(const std::string& name) {
    return parsed<std::int64_t>(name, [](std::int64_t x) { return x >= 0; }, "a voxel layer index (an integer >= 0)");
  }

  void reject_unknown() {
    for (const auto& [k, v] : fields) {
      bool known = false;
      for (const auto& u : used) known = known || u == k;
      if (!known) {
        std::string list;
        for (const auto& u : allowed) list += (list.empty() ? "" : ", ") + u;
        errors.push_back({prefix + "/" + k, "unknown parameter; allowed here: " + list});
      }
    }
  }
  std::vector<std::string> allowed;
};

int axis_index(const std::string& a) { return a[0] - 'x'; }

// Each one costs worker time and disk; a client that wants more asks the
// routes afterwards.
constexpr std::size_t kMaxAnalyses = 64;

}  // namespace

AnalysisRequest parse_analysis_request(AnalysisKind kind, const Fields& given, const std::string& path_prefix) {
  // A '+' left unescaped in a URL query arrives as a space: "+z" as " z".
  Fields fields = given;
  for (auto& [k, v] : fields)
    if (k == "view" && v.size() == 2 && v[0] == ' ') v[0] = '+';
  FieldReader in{fields, path_prefix, {}, {}, {}};
  AnalysisRequest r;
  r.kind = kind;
  auto axis = [&] { return axis_index(in.choice("axis", {"x", "y", "z"}, "z")); };
  auto peel = [&] {
    if (auto n = in.count("peel")) r.peel = *n;
    r.peel_metric = in.choice("peel_metric", kPeelMetricNames, PeelMetric::faces);
  };
  switch (kind) {
    case AnalysisKind::analysis:
      in.allowed = {"cleanup", "thickness", "skin", "min_wall", "max_wall", "peel_metric"};
      r.peel_metric = in.choice("peel_metric", kPeelMetricNames, PeelMetric::faces);
      r.cleanup = in.choice("cleanup", {"none", "debris", "sheets"}, "none");
      r.thickness = in.choice("thickness", {"true", "false"}, "true") == "true";
      r.skin = in.choice("skin", {"true", "false"}, "true") == "true";
      r.min_wall = in.positive("min_wall");
      r.max_wall = in.positive("max_wall");
      if ((r.min_wall || r.max_wall) && !r.thickness)
        in.errors.push_back({path_prefix + "/thickness", "min_wall and max_wall need the thickness analysis; drop thickness=false"});
      break;
    case AnalysisKind::radiography:
      in.allowed = {"axis", "measure", "format", "unit", "peel", "peel_metric"};
      r.axis = axis();
      peel();
      r.measure = in.choice("measure", kRadiographyMeasureNames, RadiographyMeasure::max);
      r.format = in.choice("format", {"png16", "png", "json"}, "png16");
      r.unit = in.choice("unit", {"voxels", "model"}, "voxels");
      break;
    case AnalysisKind::section:
      in.allowed = {"axis", "index", "coordinate", "colour", "peel", "peel_metric"};
      r.axis = axis();
      peel();
      r.index = in.count("index");
      r.coordinate = in.finite("coordinate");
      r.colour = in.choice("colour", {"none", "thickness", "distance"}, "none");
      if (r.index.has_value() == r.coordinate.has_value() && in.errors.empty())
        in.errors.push_back({path_prefix + "/index", "give exactly one of index (voxel layer) or coordinate (model units)"});
      break;
    case AnalysisKind::preview:
      in.allowed = {"view", "colour"};
      r.view = in.choice("view", {"+x", "-x", "+y", "-y", "+z", "-z"}, "+z");
      r.colour = in.choice("colour", {"none", "thickness", "distance"}, "none");
      break;
    case AnalysisKind::thickness:
      in.allowed = {"measure", "format", "unit"};
      r.thickness_measure = in.choice("measure", kThicknessMeasureNames, ThicknessMeasure::wall);
      r.format = in.choice("format", {"nrrd", "raw", "rle"}, "nrrd");
      r.unit = in.choice("unit", {"model", "voxels"}, "model");
      break;
  }
  in.reject_unknown();
  if (!in.errors.empty()) throw InvalidParams(std::move(in.errors));
  return r;
}

std::string AnalysisRequest::peel_query() const {
  // Only when peeling, so the plain requests keep their short URLs.
  return peel > 0 ? "&peel=" + std::to_string(peel) + "&peel_metric=" + to_string(peel_metric) : std::string();
}

std::string AnalysisRequest::query() const {
  const std::string a(1, "xyz"[axis]);
  switch (kind) {
    case AnalysisKind::analysis: {
      std::string q = "cleanup=" + cleanup + "&thickness=" + (thickness ? "true" : "false");
      if (min_wall) q += "&min_wall=" + number_text(*min_wall);
      if (max_wall) q += "&max_wall=" + number_text(*max_wall);
      if (peel_metric != PeelMetric::faces) q += std::string("&peel_metric=") + to_string(peel_metric);
      if (!skin) q += "&skin=false";  // after the rest, so URLs of earlier releases stay the same
      return q;
    }
    case AnalysisKind::radiography:
      return "axis=" + a + "&measure=" + to_string(measure) + "&format=" + format + "&unit=" + unit + peel_query();
    case AnalysisKind::section:
      return "axis=" + a + (index ? "&index=" + std::to_string(*index) : "&coordinate=" + number_text(*coordinate)) +
             "&colour=" + colour + peel_query();
    case AnalysisKind::preview: return "view=" + std::string(view[0] == '+' ? "%2B" : "-") + view.substr(1) + "&colour=" + colour;
    case AnalysisKind::thickness:
      return "measure=" + std::string(to_string(thickness_measure)) + "&format=" + format + "&unit=" + unit;
  }
  return {};
}

std::string AnalysisRequest::artifact_key() const {
  // File-name safe: the query with its separators and signs spelled out.
  std::string key = std::string(to_string(kind)) + "_";
  for (char c : query()) {
    if (c == '&') key += "__";
    else if (c == '=') key += "-";
    else if (c == '%') key += "p";
    else if (c == '.' || c == '_' || (c >= '0' && c <= '9') || (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z')) key += c;
    else if (c == '-') key += "m";
    else key += "x";
  }
  return key;
}

const char* AnalysisRequest::content_type() const {
  switch (kind) {
    case AnalysisKind::analysis: return "application/json";
    case AnalysisKind::radiography: return format == "json" ? "application/json" : "image/png";
    case AnalysisKind::section:
    case AnalysisKind::preview: return "image/png";
    case AnalysisKind::thickness:
      return format == "rle" ? "application/vnd.voxd.rle" : format == "nrrd" ? "application/x-nrrd" : "application/octet-stream";
  }
  return "application/octet-stream";
}

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
      else if (v.is_boolean()) fields.emplace_back(k, v.get<bool>() ? "true" : "false");
      else if (v.is_number_integer()) fields.emplace_back(k, v.dump());
      else if (v.is_number()) fields.emplace_back(k, number_text(v.get<double>()));
      else {
        errors.push_back({path + "/" + k, "must be a string, number or boolean, got " + std::string(v.type_name())});
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
  switch (r.kind) {
    case AnalysisKind::analysis:
      j["peel_metric"] = to_string(r.peel_metric);
      j["cleanup"] = r.cleanup;
      j["thickness"] = r.thickness;
      j["skin"] = r.skin;
      if (r.min_wall) j["min_wall"] = *r.min_wall;
      if (r.max_wall) j["max_wall"] = *r.max_wall;
      break;
    case AnalysisKind::radiography:
      j.update({{"axis", std::string(1, "xyz"[r.axis])}, {"measure", to_string(r.measure)}, {"format", r.format}, {"unit", r.unit},
                {"peel", r.peel}, {"peel_metric", to_string(r.peel_metric)}});
      break;
    case AnalysisKind::section:
      j["axis"] = std::string(1, "xyz"[r.axis]);
      if (r.index) j["index"] = *r.index;
      if (r.coordinate) j["coordinate"] = *r.coordinate;
      j["colour"] = r.colour;
      j["peel"] = r.peel;
      j["peel_metric"] = to_string(r.peel_metric);
      break;
    case AnalysisKind::preview: j.update({{"view", r.view}, {"colour", r.colour}}); break;
    case AnalysisKind::thickness:
      j.update({{"measure", to_string(r.thickness_measure)}, {"format", r.format}, {"unit", r.unit}});
      break;
  }
  return j;
}

}  // namespace voxd::api
