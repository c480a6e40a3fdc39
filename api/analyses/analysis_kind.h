#pragma once
// One kind of analysis (GET /v1/jobs/{id}/<kind>, an entry of the job JSON's
// "analyses") as one unit, on the request side: its fields and their checks,
// its canonical query (the key its result is kept under), its JSON and the
// media type of its result. Each kind lives in its own file under
// api/analyses/ and is listed once in analysis_kinds.cpp; what it computes
// is its other half, server/jobs/analyses/ (docs/architecture.md, "Adding
// an analysis").
#include <cmath>
#include <initializer_list>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "api/analysis_request.h"
#include "api/param_error.h"
#include "voxd/encode/number_text.h"
#include "voxd/enum_names.h"

namespace voxd::api {

// A request's fields as given (a URL query, an "analyses" entry), read one by
// one with the checks a field needs; every problem is kept, at prefix/name.
class FieldReader {
 public:
  FieldReader(const Fields& fields, std::string prefix) : fields_(fields), prefix_(std::move(prefix)) {}

  // The fields this kind takes; any other is refused, listing these.
  void allow(std::vector<std::string> names) { allowed_ = std::move(names); }
  void error(const std::string& field, std::string message) { errors_.push_back({prefix_ + "/" + field, std::move(message)}); }

  // The text of `name`, or null when not given (or given twice: an error).
  const std::string* find(const std::string& name);

  template <typename E, std::size_t N>
  E choice(const std::string& name, const EnumNames<E, N>& names, E fallback) {
    const std::string* v = find(name);
    if (!v) return fallback;
    if (const auto value = value_named(names, *v)) return *value;
    error(name, "must be one of " + names_listed(names) + ", got '" + *v + "'");
    return fallback;
  }
  std::string choice(const std::string& name, std::initializer_list<const char*> allowed, const char* fallback);
  bool flag(const std::string& name, bool fallback) {
    return choice(name, {"true", "false"}, fallback ? "true" : "false") == "true";
  }
  std::optional<double> positive(const std::string& name);  // a length in model units
  std::optional<double> finite(const std::string& name);
  std::optional<std::int64_t> count(const std::string& name);  // a voxel layer index
  // axis: x | y | z (default z), as 0..2.
  int axis();
  // peel and peel_metric into r.
  void peel(AnalysisRequest& r);
  // With r.colour == `slice`: the required `slice` field, a slice
  // function's options as JSON (api/slice_options.h), into r.slice and
  // r.slice_json; otherwise `slice` is refused.
  void slice(AnalysisRequest& r);

  bool ok() const { return errors_.empty(); }
  // Refuses the fields no read asked for, then throws InvalidParams with
  // every problem, if any.
  void finish();

 private:
  template <typename T, typename Ok>
  std::optional<T> parsed(const std::string& name, Ok ok, const char* wanted);

  const Fields& fields_;
  std::string prefix_;
  std::vector<FieldError> errors_;
  std::vector<std::string> used_;
  std::vector<std::string> allowed_;
};

class AnalysisKindRequest {
 public:
  virtual ~AnalysisKindRequest() = default;
  virtual AnalysisKind kind() const = 0;
  // Reads the kind's fields into `r` (which holds the defaults): in.allow()
  // them, then read each.
  virtual void parse(FieldReader& in, AnalysisRequest& r) const = 0;
  // Every field, defaults included, in a fixed order, e.g.
  // "axis=z&measure=max&format=png16&unit=voxels" (AnalysisRequest::query).
  virtual std::string query(const AnalysisRequest& r) const = 0;
  // The fields as the job JSON's "analyses" entry and the status show them.
  virtual void add_json(const AnalysisRequest& r, nlohmann::json& j) const = 0;
  // The media type of the result.
  virtual const char* content_type(const AnalysisRequest& r) const = 0;
};

// The request side of `kind` (analysis_kinds.cpp).
const AnalysisKindRequest& analysis_kind_request(AnalysisKind kind);

// "x", "y" or "z".
inline std::string axis_name(int axis) { return std::string(1, "xyz"[axis]); }

}  // namespace voxd::api
