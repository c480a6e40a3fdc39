#include "api/job_params.h"

#include <cmath>
#include <initializer_list>
#include <string_view>

#include <nlohmann/json.hpp>

#include "api/param_error.h"
#include "voxd/error.h"
#include "voxd/transform.h"

namespace voxd::api {
namespace {

using nlohmann::json;

std::string type_name(const json& v) { return v.type_name(); }

// Collects every problem instead of stopping at the first one.
class Validator {
 public:
  std::vector<FieldError> errors;

  void fail(const std::string& path, const std::string& message) { errors.push_back({path, message}); }

  bool is_object(const json& v, const std::string& path) {
    if (v.is_object()) return true;
    fail(path, "must be an object, got " + type_name(v));
    return false;
  }

  void allow_keys(const json& obj, const std::string& path, std::initializer_list<std::string_view> keys) {
    for (const auto& [key, value] : obj.items()) {
      bool known = false;
      for (auto k : keys) known = known || key == k;
      if (!known) {
        std::string list;
        for (auto k : keys) list += (list.empty() ? "" : ", ") + std::string(k);
        fail(path + "/" + key, "unknown field; allowed here: " + list);
      }
    }
  }

  std::optional<double> number(const json& obj, const std::string& path, const char* key, double lo, double hi,
                               bool lo_exclusive) {
    if (!obj.contains(key)) return std::nullopt;
    const json& v = obj.at(key);
    const std::string p = path + "/" + key;
    if (!v.is_number()) {
      fail(p, "must be a number, got " + type_name(v));
      return std::nullopt;
    }
    const double d = v.get<double>();
    if (!std::isfinite(d) || (lo_exclusive ? d <= lo : d < lo) || d > hi) {
      fail(p, "must be " + std::string(lo_exclusive ? "> " : ">= ") + fmt(lo) + " and <= " + fmt(hi) + ", got " + v.dump());
      return std::nullopt;
    }
    return d;
  }

  std::optional<std::int64_t> integer(const json& obj, const std::string& path, const char* key, std::int64_t lo,
                                      std::int64_t hi) {
    if (!obj.contains(key)) return std::nullopt;
    return integer_value(obj.at(key), path + "/" + key, lo, hi);
  }

  std::optional<std::int64_t> integer_value(const json& v, const std::string& p, std::int64_t lo, std::int64_t hi) {
    if (!v.is_number_integer()) {
      fail(p, "must be an integer, got " + (v.is_number() ? v.dump() : type_name(v)));
      return std::nullopt;
    }
    const auto i = v.get<std::int64_t>();
    if (v.is_number_unsigned() && v.get<std::uint64_t>() > static_cast<std::uint64_t>(hi)) {
      fail(p, "must be between " + std::to_string(lo) + " and " + std::to_string(hi) + ", got " + v.dump());
      return std::nullopt;
    }
    if (i < lo || i > hi) {
      fail(p, "must be between " + std::to_string(lo) + " and " + std::to_string(hi) + ", got " + v.dump());
      return std::nullopt;
    }
    return i;
  }

  std::optional<std::string> one_of(const json& obj, const std::string& path, const char* key,
                                    std::initializer_list<std::string_view> allowed) {
    if (!obj.contains(key)) return std::nullopt;
    const json& v = obj.at(key);
    const std::string p = path + "/" + key;
    std::string list;
    for (auto a : allowed) list += (list.empty() ? "" : ", ") + std::string("\"") + std::string(a) + "\"";
    if (!v.is_string()) {
      fail(p, "must be one of " + list + ", got " + type_name(v));
      return std::nullopt;
    }
    const auto s = v.get<std::string>();
    for (auto a : allowed)
      if (s == a) return s;
    fail(p, "must be one of " + list + ", got \"" + s + "\"");
    return std::nullopt;
  }

  std::optional<glm::dvec3> vec3(const json& obj, const std::string& path, const char* key) {
    if (!obj.contains(key)) return std::nullopt;
    const json& v = obj.at(key);
    const std::string p = path + "/" + key;
    if (!v.is_array() || v.size() != 3) {
      fail(p, "must be an array of 3 numbers");
      return std::nullopt;
    }
    glm::dvec3 out;
    bool ok = true;
    for (int i = 0; i < 3; ++i) {
      if (!v[i].is_number() || !std::isfinite(v[i].get<double>())) {
        fail(p + "/" + std::to_string(i), "must be a finite number, got " + v[i].dump());
        ok = false;
      } else {
        out[i] = v[i].get<double>();
      }
    }
    return ok ? std::optional(out) : std::nullopt;
  }

  static std::string fmt(double d) {
    json j = d;
    return j.dump();
  }
};

void parse_grid(Validator& val, const json& g, JobParams& out) {
  const std::string path = "/grid";
  if (!val.is_object(g, path)) return;
  const bool has_res = g.contains("resolution"), has_size = g.contains("voxel_size"), has_origin = g.contains("origin"),
             has_dims = g.contains("dims");
  if (has_res && (has_size || has_origin || has_dims)) {
    val.fail(path, "give either resolution (+ padding), voxel_size (+ padding), or voxel_size + origin + dims");
    return;
  }
  if (has_origin != has_dims) {
    val.fail(path, "an explicit grid needs origin, voxel_size and dims together");
    return;
  }
  GridRequest& r = out.grid;
  if (has_origin) {
    val.allow_keys(g, path, {"voxel_size", "origin", "dims"});
    r.kind = GridRequest::Kind::explicit_grid;
    if (!has_size) val.fail(path + "/voxel_size", "required with origin and dims");
    if (auto h = val.number(g, path, "voxel_size", 0.0, 1e30, true)) r.voxel_size = *h;
    if (auto o = val.vec3(g, path, "origin")) r.origin = *o;
    const json& d = g.at("dims");
    if (!d.is_array() || d.size() != 3) {
      val.fail(path + "/dims", "must be an array of 3 integers");
    } else {
      for (int i = 0; i < 3; ++i)
        if (auto n = val.integer_value(d[i], path + "/dims/" + std::to_string(i), 1, kMaxGridDim)) r.dims[i] = *n;
    }
    return;
  }
  val.allow_keys(g, path, {"resolution", "voxel_size", "padding"});
  if (auto p = val.integer(g, path, "padding", 0, 4096)) r.padding = *p;
  if (has_size) {
    r.kind = GridRequest::Kind::voxel_size;
    if (auto h = val.number(g, path, "voxel_size", 0.0, 1e30, true)) r.voxel_size = *h;
  } else {
    r.kind = GridRequest::Kind::resolution;
    if (auto n = val.integer(g, path, "resolution", 1, kMaxGridDim)) r.resolution = *n;
  }
}

void parse_rotation(Validator& val, const json& rot, JobParams& out) {
  const std::string path = "/rotation";
  if (!val.is_object(rot, path)) return;
  if (rot.contains("quaternion")) {
    val.allow_keys(rot, path, {"quaternion"});
    const json& q = rot.at("quaternion");
    if (!q.is_array() || q.size() != 4) {
      val.fail(path + "/quaternion", "must be an array of 4 numbers [w, x, y, z]");
      return;
    }
    double c[4];
    for (int i = 0; i < 4; ++i) {
      if (!q[i].is_number() || !std::isfinite(q[i].get<double>())) {
        val.fail(path + "/quaternion/" + std::to_string(i), "must be a finite number");
        return;
      }
      c[i] = q[i].get<double>();
    }
    if (c[0] == 0 && c[1] == 0 && c[2] == 0 && c[3] == 0) {
      val.fail(path + "/quaternion", "must not be all zeros");
      return;
    }
    out.rotation = rotation_from_quaternion(c[0], c[1], c[2], c[3]);
    return;
  }
  val.allow_keys(rot, path, {"axis", "angle_deg"});
  const auto axis = val.vec3(rot, path, "axis");
  const auto angle = val.number(rot, path, "angle_deg", -1e6, 1e6, false);
  if (!rot.contains("axis")) val.fail(path + "/axis", "required (or give quaternion)");
  if (!rot.contains("angle_deg")) val.fail(path + "/angle_deg", "required with axis");
  if (axis && angle) {
    if (axis->x == 0 && axis->y == 0 && axis->z == 0) {
      val.fail(path + "/axis", "must not be the zero vector");
      return;
    }
    out.rotation = rotation_from_axis_angle(*axis, *angle);
  }
}

void parse_coverage(Validator& val, const json& c, CoverageParams& out) {
  const std::string path = "/coverage";
  if (!val.is_object(c, path)) return;
  val.allow_keys(c, path, {"sampling", "rays", "points", "seed", "threshold", "values"});
  if (auto s = val.one_of(c, path, "sampling", {"exact", "uniform", "stochastic"}))
    out.options.sampling = *s == "exact" ? CoverageSampling::exact : *s == "uniform" ? CoverageSampling::uniform
                                                                                      : CoverageSampling::stochastic;
  if (auto k = val.integer(c, path, "rays", 1, 64)) out.options.rays = static_cast<int>(*k);
  if (auto m = val.integer(c, path, "points", 1, 256)) out.options.points = static_cast<int>(*m);
  // Options that the chosen sampling would silently ignore are refused, so a
  // client never believes it set something it did not.
  if (c.contains("points") && out.options.sampling != CoverageSampling::uniform)
    val.fail(path + "/points", "points per voxel apply only to sampling \"uniform\" (the paper's point sampling); "
                               "\"exact\" and \"stochastic\" integrate along each ray exactly");
  if (c.contains("seed")) {
    const json& v = c.at("seed");
    if (!v.is_number_integer() || (v.is_number_integer() && !v.is_number_unsigned() && v.get<std::int64_t>() < 0))
      val.fail(path + "/seed", "must be a non-negative integer, got " + v.dump());
    else
      out.options.seed = v.get<std::uint64_t>();
    if (out.options.sampling != CoverageSampling::stochastic)
      val.fail(path + "/seed", "the seed applies only to sampling \"stochastic\" (the other samplings place rays regularly)");
  }
  if (auto t = val.number(c, path, "threshold", 0.0, 1.0, true)) out.threshold = static_cast<float>(*t);
  if (auto v = val.one_of(c, path, "values", {"u8", "f32"})) out.float_values = *v == "f32";
  if (c.contains("threshold") && c.contains("values"))
    val.fail(path + "/values", "with a threshold the volume is bits (coverage >= threshold); drop one of the two");
}

void parse_sdf(Validator& val, const json& d, SdfOptions& out) {
  const std::string path = "/sdf";
  if (!val.is_object(d, path)) return;
  val.allow_keys(d, path, {"band", "sign_convention", "units"});
  if (d.contains("band")) {
    const json& b = d.at("band");
    if (b.is_string()) {
      if (b.get<std::string>() == "full")
        out.full = true;
      else
        val.fail(path + "/band", "must be a number of voxels (> 0 and <= 1000) or \"full\", got " + b.dump());
    } else if (auto w = val.number(d, path, "band", 0.0, 1000.0, true)) {
      out.band = *w;
    }
  }
  if (auto s = val.one_of(d, path, "sign_convention", {"inside_negative", "inside_positive"}))
    out.sign = *s == "inside_negative" ? SignConvention::inside_negative : SignConvention::inside_positive;
  if (auto u = val.one_of(d, path, "units", {"model", "voxels"})) out.model_units = *u == "model";
}

}  // namespace

std::string JobParams::mode_name() const {
  if (coverage) return "coverage";
  if (sdf) return "sdf";
  return to_string(mode);
}

JobParams parse_job_params(const json& params) {
  Validator val;
  JobParams out;
  if (!val.is_object(params, "")) throw InvalidParams(std::move(val.errors));
  val.allow_keys(params, "", {"grid", "mode", "inside", "rotation", "orient", "analyses", "coverage", "sdf"});
  if (params.contains("grid")) parse_grid(val, params.at("grid"), out);
  if (params.contains("rotation")) parse_rotation(val, params.at("rotation"), out);
  if (auto o = val.one_of(params, "", "orient", {"none", "auto"})) out.orient_auto = *o == "auto";
  const auto mode = val.one_of(params, "", "mode", {"solid", "surface", "solid+surface", "coverage", "sdf"});
  if (mode == "surface") out.mode = VoxelMode::surface;
  if (mode == "solid+surface") out.mode = VoxelMode::solid_and_surface;
  if (mode == "coverage") out.coverage.emplace();
  if (mode == "sdf") out.sdf.emplace();
  for (const char* options : {"coverage", "sdf"}) {
    if (!params.contains(options) || (params.contains("mode") && !mode)) continue;  // a bad mode is reported already
    if (mode.value_or("solid") != options)
      val.fail(std::string("/") + options, std::string("options for mode \"") + options + "\", but the mode is \"" +
                                               mode.value_or("solid") + "\"; set \"mode\": \"" + options + "\" or drop them");
    else if (out.coverage)
      parse_coverage(val, params.at(options), *out.coverage);
    else
      parse_sdf(val, params.at(options), *out.sdf);
  }
  if (auto i = val.one_of(params, "", "inside", {"parity", "vote", "winding"}))
    out.inside = *i == "parity" ? InsideTest::parity : *i == "vote" ? InsideTest::vote : InsideTest::winding;
  if (out.sdf) out.sdf->inside = out.inside;
  if (out.coverage && params.contains("inside"))
    val.fail("/inside", "coverage counts crossings along rays (parity); the inside test does not apply to it");
  if (params.contains("analyses")) {
    try {
      out.analyses = parse_analyses(params.at("analyses"));
    } catch (const InvalidParams& e) {
      val.errors.insert(val.errors.end(), e.errors().begin(), e.errors().end());
    }
  }
  if (!val.errors.empty()) throw InvalidParams(std::move(val.errors));
  return out;
}

JobParams parse_job_params_text(const std::string& text) {
  json j;
  try {
    j = json::parse(text);
  } catch (const json::parse_error& e) {
    throw InvalidParams({{"", std::string("malformed JSON: ") + e.what()}});
  }
  return parse_job_params(j);
}

}  // namespace voxd::api
