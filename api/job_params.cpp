#include "api/job_params.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <initializer_list>
#include <string_view>

#include <nlohmann/json.hpp>

#include "api/bounded_json.h"
#include "api/param_error.h"
#include "api/param_validator.h"
#include "voxd/error.h"
#include "voxd/transform.h"

namespace voxd::api {
namespace {

using nlohmann::json;

using Validator = ParamValidator;

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

constexpr std::string_view kInsideChoiceNames[] = {"auto", "parity", "vote", "winding"};

}  // namespace

JobParams::JobParams() : mode(job_modes().front()) {}

JobParams parse_job_params(const json& params) {
  Validator val;
  JobParams out;
  if (!val.is_object(params, "")) throw InvalidParams(std::move(val.errors));
  std::vector<std::string_view> keys = {"grid", "mode", "inside", "units", "rotation", "orient", "analyses", "streaming", "device"};
  std::vector<std::string_view> names;
  for (const JobMode* m : job_modes()) {
    names.push_back(m->name());
    if (m->has_options()) keys.push_back(m->name());
  }
  val.allow_keys(params, "", keys);
  if (params.contains("grid")) parse_grid(val, params.at("grid"), out);
  if (params.contains("rotation")) parse_rotation(val, params.at("rotation"), out);
  if (auto o = val.one_of(params, "", "orient", {"none", "auto"})) out.orient_auto = *o == "auto";
  const auto mode = val.one_of(params, "", "mode", names);
  if (mode) out.mode = find_job_mode(*mode);
  // The chosen mode's options, defaulted when the job JSON has none (a mode
  // may require them); another mode's options are refused.
  if (out.mode->has_options() && !params.contains(out.mode->name())) out.options = out.mode->parse_options(val, nullptr, out);
  for (const JobMode* m : job_modes()) {
    const std::string key(m->name());
    if (!m->has_options() || !params.contains(key) || (params.contains("mode") && !mode)) continue;  // a bad mode is reported already
    if (m != out.mode)
      val.fail("/" + key, "options for mode \"" + key + "\", but the mode is \"" + out.mode_name() + "\"; set \"mode\": \"" +
                              key + "\" or drop them");
    else
      out.options = m->parse_options(val, &params.at(key), out);
  }
  // "auto" or a test by name; a mode that counts crossings itself takes none
  // (it refuses the key) and is parity whatever the mesh.
  if (auto i = val.one_of(params, "", "inside", std::span<const std::string_view>(kInsideChoiceNames))) {
    out.inside_auto = *i == "auto";
    if (!out.inside_auto) out.inside = *value_named(kInsideTestNames, *i);
  }
  if (!out.mode->uses_inside_test()) out.inside_auto = false;
  if (auto u = val.one_of(params, "", "units", kLengthUnitNames)) out.units = *u;
  if (auto s = val.one_of(params, "", "streaming", kStreamingNames)) out.streaming = *s;
  if (auto d = val.one_of(params, "", "device", kComputeDeviceNames)) {
    out.device = *d;
    // Whether this machine has a GPU is for the one that runs the job to
    // say (prepare_voxel_job): a client validates the JSON without one.
    if (*d == ComputeDevice::cuda && !out.mode->runs_on_gpu())
      val.fail("/device", "mode \"" + out.mode_name() + "\" runs only on the CPU; drop \"device\" or use auto or cpu");
  }
  out.mode->complete(val, params, out);
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
    j = parse_bounded_json(text, "the job parameters");
  } catch (const InvalidJson& e) {
    const bool malformed = e.reason() == InvalidJson::Reason::malformed;
    throw InvalidParams(std::vector<FieldError>{{"", (malformed ? "malformed JSON: " : "") + std::string(e.what())}});
  }
  return parse_job_params(j);
}

}  // namespace voxd::api
