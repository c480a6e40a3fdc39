#include "api/job_params.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <initializer_list>
#include <string_view>

#include <nlohmann/json.hpp>

#include "api/bounded_json.h"
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
      fail(p, "must be " + std::string(lo_exclusive ? "> " : ">= ") + fmt(lo) + " and <= " + fmt(hi) + ", got " + brief_json(v));
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
      fail(p, "must be an integer, got " + (v.is_number() ? brief_json(v) : type_name(v)));
      return std::nullopt;
    }
    const auto i = v.get<std::int64_t>();
    if (v.is_number_unsigned() && v.get<std::uint64_t>() > static_cast<std::uint64_t>(hi)) {
      fail(p, "must be between " + std::to_string(lo) + " and " + std::to_string(hi) + ", got " + brief_json(v));
      return std::nullopt;
    }
    if (i < lo || i > hi) {
      fail(p, "must be between " + std::to_string(lo) + " and " + std::to_string(hi) + ", got " + brief_json(v));
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
    fail(p, "must be one of " + list + ", got " + brief_json(v));
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
        fail(p + "/" + std::to_string(i), "must be a finite number, got " + brief_json(v[i]));
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
      val.fail(path + "/seed", "must be a non-negative integer, got " + brief_json(v));
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
        val.fail(path + "/band", "must be a number of voxels (> 0 and <= 1000) or \"full\", got " + brief_json(b));
    } else if (auto w = val.number(d, path, "band", 0.0, 1000.0, true)) {
      out.band = *w;
    }
  }
  if (auto s = val.one_of(d, path, "sign_convention", {"inside_negative", "inside_positive"}))
    out.sign = *s == "inside_negative" ? SignConvention::inside_negative : SignConvention::inside_positive;
  if (auto u = val.one_of(d, path, "units", {"model", "voxels"})) out.model_units = *u == "model";
}

// A colour: [r, g, b] or [r, g, b, a] (0..255, alpha defaults to 255) or
// "#rrggbb" / "#rrggbbaa". Alpha 0 is refused: it marks empty voxels.
std::optional<Rgba8> parse_color(Validator& val, const json& v, const std::string& path) {
  const std::string hint = "must be a colour: [r, g, b], [r, g, b, a] (integers 0 to 255) or \"#rrggbb\" / \"#rrggbbaa\"";
  std::array<int, 4> c{0, 0, 0, 255};
  if (v.is_array() && (v.size() == 3 || v.size() == 4)) {
    for (std::size_t i = 0; i < v.size(); ++i) {
      const auto x = val.integer_value(v[i], path + "/" + std::to_string(i), 0, 255);
      if (!x) return std::nullopt;
      c[i] = static_cast<int>(*x);
    }
  } else if (v.is_string() && (v.get<std::string>().size() == 7 || v.get<std::string>().size() == 9) &&
             v.get<std::string>()[0] == '#' &&
             v.get<std::string>().find_first_not_of("0123456789abcdefABCDEF", 1) == std::string::npos) {
    const std::string h = v.get<std::string>();
    for (std::size_t i = 0; 1 + 2 * i < h.size(); ++i) c[i] = std::stoi(h.substr(1 + 2 * i, 2), nullptr, 16);
  } else {
    val.fail(path, hint + ", got " + brief_json(v));
    return std::nullopt;
  }
  if (c[3] == 0) {
    val.fail(path, "alpha 0 marks empty voxels; give a colour with alpha 1 to 255");
    return std::nullopt;
  }
  return Rgba8{static_cast<std::uint8_t>(c[0]), static_cast<std::uint8_t>(c[1]), static_cast<std::uint8_t>(c[2]),
               static_cast<std::uint8_t>(c[3])};
}

// A list of `lo`..`hi` colours.
std::optional<std::vector<Rgba8>> parse_colors(Validator& val, const json& obj, const std::string& path, const char* key,
                                               std::size_t lo, std::size_t hi) {
  if (!obj.contains(key)) return std::nullopt;
  const json& v = obj.at(key);
  const std::string p = path + "/" + key;
  if (!v.is_array() || v.size() < lo || v.size() > hi) {
    val.fail(p, "must be an array of " + (lo == hi ? std::to_string(lo) : std::to_string(lo) + " to " + std::to_string(hi)) +
                    " colours");
    return std::nullopt;
  }
  std::vector<Rgba8> out;
  for (std::size_t i = 0; i < v.size(); ++i) {
    const auto c = parse_color(val, v[i], p + "/" + std::to_string(i));
    if (!c) return std::nullopt;
    out.push_back(*c);
  }
  return out;
}

std::optional<std::uint64_t> parse_seed(Validator& val, const json& obj, const std::string& path) {
  if (!obj.contains("seed")) return std::nullopt;
  const json& v = obj.at("seed");
  if (!v.is_number_integer() || (!v.is_number_unsigned() && v.get<std::int64_t>() < 0)) {
    val.fail(path + "/seed", "must be a non-negative integer, got " + brief_json(v));
    return std::nullopt;
  }
  return v.get<std::uint64_t>();
}

void parse_slice(Validator& val, const json& d, SliceOptions& out) {
  const std::string path = "/slice";
  if (!val.is_object(d, path)) return;
  val.allow_keys(d, path, {"function", "axis", "color", "ramp", "corners", "checker_colors", "checker_size", "seed",
                           "noise_scale", "octaves", "period", "turbulence", "noise_colors", "lookup"});
  if (!d.contains("function")) {
    val.fail(path + "/function",
             "required: one of single_color, color_ramp, interpolated_colors, checker, wood, marble, rock, custom");
    return;
  }
  const auto f = val.one_of(d, path, "function",
                            {"single_color", "color_ramp", "interpolated_colors", "checker", "wood", "marble", "rock", "custom"});
  if (!f) return;
  out.function = *slice_function_from_string(*f);
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
      val.fail(path + "/" + key, std::string("applies only to function ") + functions + ", not \"" + *f + "\"");
    return d.contains(key) && applies;
  };
  if (only_for("color", out.function == SliceFunction::single_color, "single_color"))
    if (auto c = parse_color(val, d.at("color"), path + "/color")) out.color = *c;
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
          if (auto c = parse_color(val, r[i].at("color"), p + "/color")) stop.color = *c;
        if (!stops.empty() && stop.position < stops.back().position)
          val.fail(p + "/position", "stops must be in order of position (non-decreasing)");
        stops.push_back(stop);
      }
      out.ramp = std::move(stops);
    }
  }
  if (only_for("corners", out.function == SliceFunction::interpolated_colors, "interpolated_colors"))
    if (auto c = parse_colors(val, d, path, "corners", 4, 4)) std::copy(c->begin(), c->end(), out.corners.begin());
  if (only_for("checker_colors", out.function == SliceFunction::checker, "checker"))
    if (auto c = parse_colors(val, d, path, "checker_colors", 2, 2)) std::copy(c->begin(), c->end(), out.checker_colors.begin());
  if (only_for("checker_size", out.function == SliceFunction::checker, "checker"))
    if (auto x = val.number(d, path, "checker_size", 0.0, 1e30, true)) out.checker_size = *x;
  if (only_for("seed", noise, "wood, marble or rock"))
    if (auto x = parse_seed(val, d, path)) out.seed = *x;
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
    if (auto c = parse_colors(val, d, path, "noise_colors", 2, 3)) out.noise_colors = *c;
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
          if (auto c = parse_colors(val, l, lp, "colors", cells, cells)) out.lookup_colors = *c;
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

// A custom palette element: {"name", "pieces": [[[nx, ny, nz, d], ...], ...], "complement": bool}.
void parse_custom_element(Validator& val, const json& e, const std::string& p, Palette& palette) {
  if (!val.is_object(e, p)) return;
  val.allow_keys(e, p, {"name", "pieces", "complement"});
  PaletteElement element;
  if (!e.contains("name") || !e.at("name").is_string() || e.at("name").get<std::string>().empty() ||
      e.at("name").get<std::string>().size() > 64) {
    val.fail(p + "/name", "required: a name of 1 to 64 characters");
    return;
  }
  element.name = e.at("name").get<std::string>();
  if (!e.contains("pieces") || !e.at("pieces").is_array() || e.at("pieces").size() > kMaxPieces) {
    val.fail(p + "/pieces", "required: an array of at most " + std::to_string(kMaxPieces) +
                                " convex pieces, each an array of half-spaces [nx, ny, nz, d] meaning "
                                "nx x + ny y + nz z <= d in the unit voxel [0, 1]^3 ([] is the whole voxel)");
    return;
  }
  const json& pieces = e.at("pieces");
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    const std::string pp = p + "/pieces/" + std::to_string(i);
    if (!pieces[i].is_array() || pieces[i].size() > kMaxHalfSpaces) {
      val.fail(pp, "must be an array of at most " + std::to_string(kMaxHalfSpaces) + " half-spaces [nx, ny, nz, d]");
      return;
    }
    ConvexPiece piece;
    for (std::size_t h = 0; h < pieces[i].size(); ++h) {
      const json& hs = pieces[i][h];
      const std::string hp = pp + "/" + std::to_string(h);
      bool ok = hs.is_array() && hs.size() == 4;
      for (std::size_t c = 0; ok && c < 4; ++c) ok = hs[c].is_number() && std::isfinite(hs[c].get<double>());
      if (!ok) {
        val.fail(hp, "must be [nx, ny, nz, d], four finite numbers: nx x + ny y + nz z <= d");
        return;
      }
      const HalfSpace half{{hs[0].get<double>(), hs[1].get<double>(), hs[2].get<double>()}, hs[3].get<double>()};
      if (half.normal == glm::dvec3(0.0)) {
        val.fail(hp, "the normal (nx, ny, nz) must not be zero");
        return;
      }
      piece.push_back(half);
    }
    element.pieces.push_back(std::move(piece));
  }
  if (e.contains("complement")) {
    if (!e.at("complement").is_boolean()) {
      val.fail(p + "/complement", "must be true or false");
      return;
    }
    if (e.at("complement").get<bool>()) {
      try {
        element = complement_of(element, element.name);
      } catch (const Error& err) {
        val.fail(p + "/complement", err.what());
        return;
      }
    }
  }
  if (palette.find(element.name)) {
    val.fail(p + "/name", "\"" + element.name + "\" names two elements");
    return;
  }
  palette.elements.push_back(std::move(element));
}

// "render": {"<element name>": [{"object": name, "min_similarity": D}, ...], ...}
void parse_render(Validator& val, const json& r, PaletteParams& out) {
  const std::string path = "/palette/render";
  if (!val.is_object(r, path)) return;
  const Palette& palette = out.options.palette;
  out.render.by_element.assign(palette.elements.size(), {});
  for (const auto& [name, list] : r.items()) {
    const std::string p = path + "/" + name;
    const auto element = palette.find(name);
    if (!element) {
      val.fail(p, "no element of the palette is named \"" + name + "\" (see GET /v1/jobs/{id}/palette for the names)");
      continue;
    }
    if (!list.is_array() || list.empty() || list.size() > 16) {
      val.fail(p, "must be an array of 1 to 16 display objects {\"object\": name, \"min_similarity\": 0..1}");
      continue;
    }
    for (std::size_t i = 0; i < list.size(); ++i) {
      const std::string op = p + "/" + std::to_string(i);
      if (!val.is_object(list[i], op)) continue;
      val.allow_keys(list[i], op, {"object", "min_similarity"});
      if (!list[i].contains("object") || !list[i].at("object").is_string() || list[i].at("object").get<std::string>().empty()) {
        val.fail(op + "/object", "required: the display object's name");
        continue;
      }
      const std::string object = list[i].at("object").get<std::string>();
      DisplayChoice choice;
      if (auto d = val.number(list[i], op, "min_similarity", 0.0, 1.0, false)) choice.min_similarity = *d;
      auto at = std::find(out.render.objects.begin(), out.render.objects.end(), object);
      if (at == out.render.objects.end()) {
        if (out.render.objects.size() == 255) {
          val.fail(op + "/object", "at most 255 distinct display objects");
          continue;
        }
        out.render.objects.push_back(object);
        at = out.render.objects.end() - 1;
      }
      choice.object = static_cast<std::uint8_t>(at - out.render.objects.begin() + 1);
      out.render.by_element[*element].push_back(choice);
    }
  }
}

void parse_palette(Validator& val, const json& d, PaletteParams& out) {
  const std::string path = "/palette";
  if (!val.is_object(d, path)) return;
  val.allow_keys(d, path, {"elements", "metric", "rays", "points", "seed", "voxel_aspect", "render"});
  if (d.contains("elements")) {
    const json& e = d.at("elements");
    if (e.is_number_integer()) {
      const auto n = e.get<std::int64_t>();
      if (n == 2 || n == 10 || n == 46 || n == 78) {
        out.options.palette = builtin_palette(static_cast<int>(n));
        out.palette_name = std::to_string(n);
      } else {
        val.fail(path + "/elements", "built-in palettes have 2, 10, 46 or 78 elements, got " + brief_json(e) +
                                         "; or give an array of custom elements");
      }
    } else if (e.is_array() && !e.empty() && e.size() <= kMaxPaletteElements) {
      Palette custom;
      const std::size_t before = val.errors.size();
      for (std::size_t i = 0; i < e.size(); ++i) parse_custom_element(val, e[i], path + "/elements/" + std::to_string(i), custom);
      if (val.errors.size() == before) {
        out.options.palette = std::move(custom);
        out.palette_name = "custom";
      }
    } else {
      val.fail(path + "/elements", "must be 2, 10, 46 or 78 (a built-in palette) or an array of 1 to " +
                                       std::to_string(kMaxPaletteElements) + " custom elements");
    }
  }
  if (auto m = val.one_of(d, path, "metric", {"nearest", "outer", "inner"})) out.options.metric = *palette_metric_from_string(*m);
  if (auto t = val.integer(d, path, "rays", 1, 256)) out.options.rays = static_cast<int>(*t);
  if (auto p = val.integer(d, path, "points", 1, 64)) out.options.points = static_cast<int>(*p);
  if (out.options.rays * out.options.points > 4096)
    val.fail(path + "/points", "rays x points must be at most 4096 sample points per voxel");
  if (auto seed = parse_seed(val, d, path)) out.options.seed = *seed;
  if (auto a = val.vec3(d, path, "voxel_aspect")) {
    if (a->x <= 0 || a->y <= 0 || a->z <= 0 || a->x > 1000 || a->y > 1000 || a->z > 1000)
      val.fail(path + "/voxel_aspect", "must be three edge ratios > 0 and <= 1000, e.g. [1, 1, 0.4]");
    else
      out.voxel_aspect = *a;
  }
  if (d.contains("render")) parse_render(val, d.at("render"), out);
}

}  // namespace

std::string JobParams::mode_name() const {
  if (coverage) return "coverage";
  if (sdf) return "sdf";
  if (palette) return "palette";
  if (slice) return "slice";
  return to_string(mode);
}

std::optional<ValueVolume> value_type_probe(const JobParams& params) {
  if (!params.has_values()) return std::nullopt;
  if (params.slice) return ValueVolume(DenseVolume<Rgba8>());
  if (params.sdf || (params.coverage && params.coverage->float_values)) return ValueVolume(DenseVolume<float>());
  return ValueVolume(DenseVolume<std::uint8_t>());
}

JobParams parse_job_params(const json& params) {
  Validator val;
  JobParams out;
  if (!val.is_object(params, "")) throw InvalidParams(std::move(val.errors));
  val.allow_keys(params, "",
                 {"grid", "mode", "inside", "rotation", "orient", "analyses", "coverage", "sdf", "palette", "slice"});
  if (params.contains("grid")) parse_grid(val, params.at("grid"), out);
  if (params.contains("rotation")) parse_rotation(val, params.at("rotation"), out);
  if (auto o = val.one_of(params, "", "orient", {"none", "auto"})) out.orient_auto = *o == "auto";
  const auto mode =
      val.one_of(params, "", "mode", {"solid", "surface", "solid+surface", "coverage", "sdf", "palette", "slice"});
  if (mode == "surface") out.mode = VoxelMode::surface;
  if (mode == "solid+surface") out.mode = VoxelMode::solid_and_surface;
  if (mode == "coverage") out.coverage.emplace();
  if (mode == "sdf") out.sdf.emplace();
  if (mode == "palette") out.palette.emplace();
  if (mode == "slice") out.slice.emplace();
  if (out.slice && !params.contains("slice"))
    val.fail("/slice", "required with mode \"slice\": at least {\"function\": ...}");
  for (const char* options : {"coverage", "sdf", "palette", "slice"}) {
    if (!params.contains(options) || (params.contains("mode") && !mode)) continue;  // a bad mode is reported already
    if (mode.value_or("solid") != options)
      val.fail(std::string("/") + options, std::string("options for mode \"") + options + "\", but the mode is \"" +
                                               mode.value_or("solid") + "\"; set \"mode\": \"" + options + "\" or drop them");
    else if (out.coverage)
      parse_coverage(val, params.at(options), *out.coverage);
    else if (out.sdf)
      parse_sdf(val, params.at(options), *out.sdf);
    else if (out.palette)
      parse_palette(val, params.at(options), *out.palette);
    else
      parse_slice(val, params.at(options), *out.slice);
  }
  if (auto i = val.one_of(params, "", "inside", {"parity", "vote", "winding"}))
    out.inside = *i == "parity" ? InsideTest::parity : *i == "vote" ? InsideTest::vote : InsideTest::winding;
  if (out.sdf) out.sdf->inside = out.inside;
  if (out.slice) out.slice->inside = out.inside;
  if ((out.coverage || out.palette) && params.contains("inside"))
    val.fail("/inside", out.mode_name() + " counts crossings along rays (parity); the inside test does not apply to it");
  if (out.palette && params.contains("mode") && out.palette->voxel_aspect != glm::dvec3(1.0) &&
      out.grid.kind == GridRequest::Kind::explicit_grid)
    val.fail("/palette/voxel_aspect", "anisotropic voxels size the grid themselves; give resolution or voxel_size, not an explicit grid");
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
