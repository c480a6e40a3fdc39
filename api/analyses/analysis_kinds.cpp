// Every analysis kind's request side, registered once, in the order of
// AnalysisKind (kAnalysisKindNames); and the field reader they share.
#include <array>
#include <stdexcept>

#include "api/analyses/analysis_kind.h"
#include "api/bounded_json.h"
#include "api/param_validator.h"
#include "api/slice_options.h"

namespace voxd::api {
namespace {

// A slice function's options are a few hundred bytes; a custom lookup of a
// few hundred cells fits too. Larger lookups are a slice job's.
constexpr std::size_t kMaxSliceBytes = 8 << 10;

}  // namespace

// Each defined in its own file under api/analyses/.
const AnalysisKindRequest& report_request();
const AnalysisKindRequest& radiography_request();
const AnalysisKindRequest& section_request();
const AnalysisKindRequest& preview_request();
const AnalysisKindRequest& thickness_request();

const AnalysisKindRequest& analysis_kind_request(AnalysisKind kind) {
  static const std::array<const AnalysisKindRequest*, kAnalysisKindNames.size()> kinds{
      &report_request(), &radiography_request(), &section_request(), &preview_request(), &thickness_request()};
  for (const AnalysisKindRequest* k : kinds)
    if (k->kind() == kind) return *k;
  throw std::logic_error("an analysis kind without its request side");
}

const std::string* FieldReader::find(const std::string& name) {
  const std::string* found = nullptr;
  for (const auto& [k, v] : fields_) {
    if (k != name) continue;
    if (found) {
      error(name, "given more than once");
      return nullptr;
    }
    found = &v;
  }
  if (found) used_.push_back(name);
  return found;
}

std::string FieldReader::choice(const std::string& name, std::initializer_list<const char*> allowed, const char* fallback) {
  const std::string* v = find(name);
  if (!v) return fallback;
  std::string list;
  for (const char* a : allowed) {
    if (*v == a) return *v;
    list += list.empty() ? a : std::string(", ") + a;
  }
  error(name, "must be one of " + list + ", got '" + *v + "'");
  return fallback;
}

// The whole text as a T that satisfies `ok`, or an error saying `wanted`.
template <typename T, typename Ok>
std::optional<T> FieldReader::parsed(const std::string& name, Ok ok, const char* wanted) {
  const std::string* v = find(name);
  if (!v) return std::nullopt;
  const std::optional<T> x = parse_number<T>(*v);
  if (!x || !ok(*x)) {
    error(name, std::string("must be ") + wanted + ", got '" + *v + "'");
    return std::nullopt;
  }
  return x;
}

std::optional<double> FieldReader::positive(const std::string& name) {
  return parsed<double>(name, [](double x) { return std::isfinite(x) && x > 0; }, "a positive length in model units");
}

std::optional<double> FieldReader::finite(const std::string& name) {
  return parsed<double>(name, [](double x) { return std::isfinite(x); }, "a number");
}

std::optional<std::int64_t> FieldReader::count(const std::string& name) {
  return parsed<std::int64_t>(name, [](std::int64_t x) { return x >= 0; }, "a voxel layer index (an integer >= 0)");
}

int FieldReader::axis() { return choice("axis", {"x", "y", "z"}, "z")[0] - 'x'; }

void FieldReader::peel(AnalysisRequest& r) {
  if (auto n = count("peel")) r.peel = *n;
  r.peel_metric = choice("peel_metric", kPeelMetricNames, PeelMetric::faces);
}

void FieldReader::slice(AnalysisRequest& r) {
  const std::string* text = find(kSliceName);
  if (!r.slice_coloured()) {
    if (text) error(kSliceName, "applies only with colour=slice (a slice function's colours on the job's solid)");
    return;
  }
  if (!text) {
    error(kSliceName, "required with colour=slice: the slice function's options as JSON, the object a slice job takes as "
                   "\"slice\", e.g. {\"function\": \"marble\", \"period\": 2}");
    return;
  }
  nlohmann::json options;
  try {
    options = parse_bounded_json(*text, kSliceName, JsonLimits{kMaxSliceBytes, 8});
  } catch (const InvalidJson& e) {
    error(kSliceName, e.what());
    return;
  }
  ParamValidator val;
  SliceOptions parsed;
  parse_slice_options(val, options, "", parsed);
  for (const FieldError& e : val.errors) errors_.push_back({prefix_ + "/" + kSliceName + e.path, e.message});
  if (!val.errors.empty()) return;
  r.slice = parsed;
  r.slice_json = slice_options_json(parsed).dump();
}

void FieldReader::finish() {
  for (const auto& [k, v] : fields_) {
    bool known = false;
    for (const auto& u : used_) known = known || u == k;
    if (!known) {
      std::string list;
      for (const auto& a : allowed_) list += (list.empty() ? "" : ", ") + a;
      error(k, "unknown parameter; allowed here: " + list);
    }
  }
  if (!errors_.empty()) throw InvalidParams(std::move(errors_));
}

}  // namespace voxd::api
