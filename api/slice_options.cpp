// A slice function's options as JSON: the job JSON's `slice` object (mode
// `slice`) and the `slice` field of a section or preview coloured by one.
#include "api/slice_options.h"

#include <algorithm>
#include <cstdio>

#include "voxd/error.h"

namespace voxd::api {

using nlohmann::json;

void parse_slice_options(ParamValidator& val, const json& d, const std::string& path, SliceOptions& out) {
  if (!val.is_object(d, path)) return;
  val.allow_keys(d, path, {"function", "axis", "color", "ramp", "corners", "checker_colors", "checker_size", "seed",
                           "noise_scale", "octaves", "period", "turbulence", "noise_colors", "lookup"});
  if (!d.contains("function")) {
    val.fail(path + "/function", "required: one of " + names_listed(kSliceFunctionNames));
    return;
  }
  const auto f = val.one_of(d, path, "function", kSliceFunctionNames);
  if (!f) return;
  out.function = *f;
  if (auto a = val.vec3(d, path, "axis")) {
    if (*a == glm::dvec3(0.0))
      val.fail(path + "/axis", "must not be the zero vector: it is the slicing direction");
    else
      out.axis = *a;
  }
  // Each function's own parameters; another function's are refused, so a
  // client never believes it set something that is ignored.
  const bool noise = out.function == SliceFunction::wood || out.function == SliceFunction::marble ||
                     out.function == SliceFunction::rock;
  const auto only_for = [&](const char* key, bool applies, const char* functions) {
    if (d.contains(key) && !applies)
      val.fail(path + "/" + key, std::string("applies only to function ") + functions + ", not \"" + to_string(*f) + "\"");
    return d.contains(key) && applies;
  };
  if (only_for("color", out.function == SliceFunction::single_color, "single_color"))
    if (auto c = val.color(d.at("color"), path + "/color")) out.color = *c;
  if (only_for("ramp", out.function == SliceFunction::color_ramp, "color_ramp")) {
    const json& r = d.at("ramp");
    if (!r.is_array() || r.size() < 2 || r.size() > 64) {
      val.fail(path + "/ramp", "must be an array of 2 to 64 stops {\"position\": 0..1, \"color\": colour}");
    } else {
      std::vector<RampStop> stops;
      for (std::size_t i = 0; i < r.size(); ++i) {
        const std::string p = path + "/ramp/" + std::to_string(i);
        if (!val.is_object(r[i], p)) continue;
        val.allow_keys(r[i], p, {"position", "color"});
        RampStop stop;
        if (!r[i].contains("position")) val.fail(p + "/position", "required");
        if (!r[i].contains("color")) val.fail(p + "/color", "required");
        if (auto x = val.number(r[i], p, "position", 0.0, 1.0, false)) stop.position = *x;
        if (r[i].contains("color"))
          if (auto c = val.color(r[i].at("color"), p + "/color")) stop.color = *c;
        if (!stops.empty() && stop.position < stops.back().position)
          val.fail(p + "/position", "stops must be in order of position (non-decreasing)");
        stops.push_back(stop);
      }
      out.ramp = std::move(stops);
    }
  }
  if (only_for("corners", out.function == SliceFunction::interpolated_colors, "interpolated_colors"))
    if (auto c = val.colors(d, path, "corners", 4, 4)) std::copy(c->begin(), c->end(), out.corners.begin());
  if (only_for("checker_colors", out.function == SliceFunction::checker, "checker"))
    if (auto c = val.colors(d, path, "checker_colors", 2, 2)) std::copy(c->begin(), c->end(), out.checker_colors.begin());
  if (only_for("checker_size", out.function == SliceFunction::checker, "checker"))
    if (auto x = val.number(d, path, "checker_size", 0.0, 1e30, true)) out.checker_size = *x;
  if (only_for("seed", noise, "wood, marble or rock"))
    if (auto x = val.seed(d, path)) out.seed = *x;
  if (only_for("noise_scale", noise, "wood, marble or rock"))
    if (auto x = val.number(d, path, "noise_scale", 0.0, 1e30, true)) out.noise_scale = *x;
  if (only_for("octaves", noise, "wood, marble or rock"))
    if (auto x = val.integer(d, path, "octaves", 1, 16)) out.octaves = static_cast<int>(*x);
  const bool periodic = out.function == SliceFunction::wood || out.function == SliceFunction::marble;
  if (only_for("period", periodic, "wood or marble"))
    if (auto x = val.number(d, path, "period", 0.0, 1e30, true)) out.period = *x;
  if (only_for("turbulence", periodic, "wood or marble"))
    if (auto x = val.number(d, path, "turbulence", 0.0, 1e6, false)) out.turbulence = *x;
  if (only_for("noise_colors", noise, "wood, marble or rock"))
    if (auto c = val.colors(d, path, "noise_colors", 2, 3)) out.noise_colors = *c;
  if (out.function == SliceFunction::custom && !d.contains("lookup"))
    val.fail(path + "/lookup", "required with function custom: {\"dims\": [nx, ny, nz], \"colors\": [...]}");
  if (only_for("lookup", out.function == SliceFunction::custom, "custom")) {
    const json& l = d.at("lookup");
    const std::string lp = path + "/lookup";
    if (val.is_object(l, lp)) {
      val.allow_keys(l, lp, {"dims", "colors"});
      const json* dims = l.contains("dims") ? &l.at("dims") : nullptr;
      if (!dims || !dims->is_array() || dims->size() != 3) {
        val.fail(lp + "/dims", "required: [nx, ny, nz], 1 to 64 cells each along the frame's a, b, c");
      } else {
        bool ok = true;
        for (std::size_t i = 0; i < 3; ++i)
          if (auto n = val.integer_value((*dims)[i], lp + "/dims/" + std::to_string(i), 1, 64))
            out.lookup_dims[i] = static_cast<int>(*n);
          else
            ok = false;
        const std::size_t cells = static_cast<std::size_t>(out.lookup_dims[0]) *
                                  static_cast<std::size_t>(out.lookup_dims[1]) * static_cast<std::size_t>(out.lookup_dims[2]);
        if (ok) {
          if (auto c = val.colors(l, lp, "colors", cells, cells)) out.lookup_colors = *c;
          else if (!l.contains("colors")) val.fail(lp + "/colors", "required: nx * ny * nz colours, x fastest");
        }
      }
    }
  }
  try {
    validate(out);  // what the checks above cannot see, e.g. a zero-extent ramp
  } catch (const Error& e) {
    val.fail(path, e.what());
  }
}

namespace {

json colour_json(const Rgba8& c) {
  char text[10];
  std::snprintf(text, sizeof text, "#%02x%02x%02x%02x", c.r, c.g, c.b, c.a);
  return text;
}

json colours_json(const Rgba8* begin, const Rgba8* end) {
  json out = json::array();
  for (const Rgba8* c = begin; c != end; ++c) out.push_back(colour_json(*c));
  return out;
}

}  // namespace

json slice_options_json(const SliceOptions& o) {
  json j{{"function", to_string(o.function)}, {"axis", {o.axis.x, o.axis.y, o.axis.z}}};
  switch (o.function) {
    case SliceFunction::single_color: j["color"] = colour_json(o.color); break;
    case SliceFunction::color_ramp: {
      json stops = json::array();
      for (const RampStop& s : o.ramp) stops.push_back({{"position", s.position}, {"color", colour_json(s.color)}});
      j["ramp"] = std::move(stops);
      break;
    }
    case SliceFunction::interpolated_colors:
      j["corners"] = colours_json(o.corners.data(), o.corners.data() + o.corners.size());
      break;
    case SliceFunction::checker:
      j["checker_colors"] = colours_json(o.checker_colors.data(), o.checker_colors.data() + o.checker_colors.size());
      j["checker_size"] = o.checker_size;
      break;
    case SliceFunction::wood:
    case SliceFunction::marble:
    case SliceFunction::rock:
      j["seed"] = o.seed;
      j["noise_scale"] = o.noise_scale;
      j["octaves"] = o.octaves;
      if (o.function != SliceFunction::rock) {
        j["period"] = o.period;
        j["turbulence"] = o.turbulence;
      }
      j["noise_colors"] = colours_json(o.noise_colors.data(), o.noise_colors.data() + o.noise_colors.size());
      break;
    case SliceFunction::custom:
      j["lookup"] = {{"dims", {o.lookup_dims[0], o.lookup_dims[1], o.lookup_dims[2]}},
                     {"colors", colours_json(o.lookup_colors.data(), o.lookup_colors.data() + o.lookup_colors.size())}};
      break;
  }
  return j;
}

}  // namespace voxd::api
