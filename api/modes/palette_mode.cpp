// "mode": "palette" (Cavagnino & Gribaudo 2010, voxd/voxelize/palette.h):
// each voxel takes the palette element most similar to the part inside it.
// Options under "palette". Beside the element indices (the result) it keeps
// each voxel's similarity, serves the display objects of a rendering palette
// as a third layer, writes its reconstruction as STL or glTF, and describes
// the palette at GET /v1/jobs/{id}/palette.
#include <algorithm>
#include <cmath>

#include <nlohmann/json.hpp>

#include "api/job_mode.h"
#include "api/job_params.h"
#include "api/param_validator.h"
#include "voxd/encode/palette_export.h"
#include "voxd/error.h"
#include "voxd/voxelize/palette.h"
#include "voxd/voxelize/palette_geometry.h"
#include "voxd/voxelize/palette_render.h"

namespace voxd::api {
namespace {

using nlohmann::json;

struct PaletteParams : ModeOptions {
  PaletteOptions options;              // palette, metric, rays, points, seed (threads set by the runner)
  std::string palette_name = "46";     // "2", "10", "46", "78" or "custom"
  glm::dvec3 voxel_aspect{1.0};        // the voxel's edges over the grid's voxel_size (anisotropic voxels)
  RenderPalette render;                // display objects by element and similarity (may be empty)
};

// A custom palette element: {"name", "pieces": [[[nx, ny, nz, d], ...], ...], "complement": bool}.
void parse_custom_element(ParamValidator& val, const json& e, const std::string& p, Palette& palette) {
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
void parse_render(ParamValidator& val, const json& r, PaletteParams& out) {
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

void parse_palette(ParamValidator& val, const json& d, PaletteParams& out) {
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
  if (auto m = val.one_of(d, path, "metric", kPaletteMetricNames)) out.options.metric = *m;
  if (auto t = val.integer(d, path, "rays", 1, 256)) out.options.rays = static_cast<int>(*t);
  if (auto p = val.integer(d, path, "points", 1, 64)) out.options.points = static_cast<int>(*p);
  if (out.options.rays * out.options.points > 4096)
    val.fail(path + "/points", "rays x points must be at most 4096 sample points per voxel");
  if (auto seed = val.seed(d, path)) out.options.seed = *seed;
  if (auto a = val.vec3(d, path, "voxel_aspect")) {
    if (a->x <= 0 || a->y <= 0 || a->z <= 0 || a->x > 1000 || a->y > 1000 || a->z > 1000)
      val.fail(path + "/voxel_aspect", "must be three edge ratios > 0 and <= 1000, e.g. [1, 1, 0.4]");
    else
      out.voxel_aspect = *a;
  }
  if (d.contains("render")) parse_render(val, d.at("render"), out);
}

json element_json(const PaletteElement& e, std::size_t index) {
  json pieces = json::array();
  for (const ConvexPiece& piece : e.pieces) {
    json halves = json::array();
    for (const HalfSpace& h : piece) halves.push_back({h.normal.x, h.normal.y, h.normal.z, h.offset});
    pieces.push_back(std::move(halves));
  }
  return {{"index", index}, {"name", e.name}, {"pieces", std::move(pieces)}, {"volume", element_volume(e)}};
}

class PaletteMode final : public ModeWithOptions<PaletteParams> {
 public:
  std::string_view name() const override { return "palette"; }
  std::string_view summary() const override {
    return "each voxel's palette element (Cavagnino & Gribaudo): bytes, or the reconstruction as stl or glb";
  }

  void parse(ParamValidator& val, const json* options, PaletteParams& out) const override {
    if (options) parse_palette(val, *options, out);
  }

  void complete(ParamValidator& val, const json& job, JobParams& params) const override {
    refuse_inside_test(val, job, name());
    if (job.contains("mode") && options(params).voxel_aspect != glm::dvec3(1.0) &&
        params.grid.kind == GridRequest::Kind::explicit_grid)
      val.fail("/palette/voxel_aspect",
               "anisotropic voxels size the grid themselves; give resolution or voxel_size, not an explicit grid");
  }

  std::optional<ValueVolume> value_type(const JobParams&) const override { return ValueVolume(DenseVolume<std::uint8_t>()); }
  glm::dvec3 voxel_aspect(const JobParams& params) const override { return options(params).voxel_aspect; }
  // Element and similarity bytes.
  std::uint64_t memory_estimate(const Grid& grid, const JobParams& params) const override {
    return bit_volumes_memory(grid, VoxelMode::solid, params.inside) + 2 * grid.voxel_count();
  }
  // The solid is the parity solid of its crossings.
  bool uses_inside_test() const override { return false; }
  bool needs_parity_solid(const JobParams&) const override { return true; }
  bool values_are_image() const override { return false; }  // element indices: sections show the solid

  JobVolumes run(const ModeInput& in) const override {
    const PaletteParams& p = options(in.params);
    PaletteOptions o = p.options;
    o.threads = in.threads;
    PaletteVolume v = voxelize_palette(in.mesh, in.grid, o, in.control);
    const glm::dvec3 a = p.voxel_aspect;
    JobVolumes result;
    result.values_info = {{"quantity", "palette element"},
                          {"unit", "element index (GET /v1/jobs/{id}/palette)"},
                          {"palette", p.palette_name},
                          {"elements", o.palette.elements.size()},
                          {"metric", to_string(o.metric)},
                          {"rays", o.rays},
                          {"points", o.points},
                          {"seed", o.seed},
                          {"voxel_aspect", {a.x, a.y, a.z}},
                          {"voxel_edges", {in.grid.voxel_size * a.x, in.grid.voxel_size * a.y, in.grid.voxel_size * a.z}},
                          {"layers", {"element", "similarity"}}};
    if (!p.render.empty()) result.values_info["layers"].push_back("display");
    result.values = std::make_shared<const ValueVolume>(std::move(v.element));
    result.layers.emplace_back("similarity", std::make_shared<const ValueVolume>(std::move(v.similarity)));
    return result;
  }

  // The reconstruction as a mesh, in model units: the engine ran where
  // voxels are cubes (coordinates / aspect), the export scales that space,
  // origin included, back.
  bool writes(VolumeFormat format) const override { return format == VolumeFormat::stl || format == VolumeFormat::glb; }
  void write(VolumeFormat format, const JobParams& params, const VolumeSource& volumes, ByteSink& sink) const override {
    const PaletteParams& p = options(params);
    const auto& element = std::get<DenseVolume<std::uint8_t>>(*volumes("values"));
    if (format == VolumeFormat::stl) return write_palette_stl(p.options.palette, element, p.voxel_aspect, sink);
    if (format == VolumeFormat::glb) return write_palette_glb(p.options.palette, element, p.voxel_aspect, sink);
    JobMode::write(format, params, volumes, sink);
  }

  std::vector<std::string> layer_names() const override { return {"element", "similarity", "display"}; }
  std::vector<std::string> stored_layers() const override { return {"similarity"}; }
  std::string layer_content(const std::string& layer, const json& values_info) const override {
    if (layer == "similarity") return "palette similarity (round(255 x the share of sample points where element and part agree))";
    if (layer == "display") return "display object (0 = nothing shown, else render.objects index of GET /v1/jobs/{id}/palette)";
    return JobMode::layer_content(layer, values_info);
  }

  std::shared_ptr<const ValueVolume> layer(const std::string& layer, const JobParams& params,
                                           const VolumeSource& volumes) const override {
    if (layer != "element" && layer != "similarity" && layer != "display")
      throw QueryRejected("layer must be element, similarity or display, got '" + layer + "'");
    auto element = volumes("values");
    if (layer == "element") return element;
    auto similarity = volumes("similarity");
    if (layer == "similarity") return similarity;
    const PaletteParams& p = options(params);
    if (p.render.empty())
      throw QueryRejected("layer display needs a rendering palette: the job JSON's \"palette\": {\"render\": ...}");
    return std::make_shared<const ValueVolume>(render_palette(std::get<DenseVolume<std::uint8_t>>(*element),
                                                              std::get<DenseVolume<std::uint8_t>>(*similarity), p.render));
  }

  std::vector<std::string> documents() const override { return {"palette"}; }

  // Each element's half-spaces, exact volume and voxel count; with a
  // rendering palette, the display objects and their counts.
  json document(const std::string&, const JobParams& params, const VolumeSource& volumes) const override {
    const PaletteParams& p = options(params);
    const auto values = volumes("values");
    const auto& element = std::get<DenseVolume<std::uint8_t>>(*values);
    std::vector<std::uint64_t> counts(p.options.palette.elements.size(), 0);
    for (std::uint8_t e : element.values())
      if (e < counts.size()) ++counts[e];
    json elements = json::array();
    for (std::size_t i = 0; i < p.options.palette.elements.size(); ++i) {
      json e = element_json(p.options.palette.elements[i], i);
      e["voxels"] = counts[i];
      elements.push_back(std::move(e));
    }
    json body = {{"palette", p.palette_name},
                 {"metric", to_string(p.options.metric)},
                 {"rays", p.options.rays},
                 {"points", p.options.points},
                 {"seed", p.options.seed},
                 {"voxel_aspect", {p.voxel_aspect.x, p.voxel_aspect.y, p.voxel_aspect.z}},
                 {"element_coordinates", "voxel coordinates [0, 1]^3; a half-space [nx, ny, nz, d] holds nx x + ny y + nz z <= d; "
                                         "an element is the union of its pieces, a piece the intersection of its half-spaces"},
                 {"similarity", "the volume's layer=similarity holds round(255 B), B the share of the voxel's sample points "
                                "where the element and the part agree; 0 also when no element was admissible"},
                 {"elements", std::move(elements)}};
    if (!p.render.empty()) {
      const auto similarity = volumes("similarity");
      const DenseVolume<std::uint8_t> shown =
          render_palette(element, std::get<DenseVolume<std::uint8_t>>(*similarity), p.render);
      std::vector<std::uint64_t> display(p.render.objects.size() + 1, 0);
      for (std::uint8_t o : shown.values()) ++display[o];
      json objects = json::array();
      for (std::size_t i = 0; i < p.render.objects.size(); ++i)
        objects.push_back({{"index", i + 1}, {"name", p.render.objects[i]}, {"voxels", display[i + 1]}});
      json rules = json::object();
      for (std::size_t e = 0; e < p.render.by_element.size(); ++e) {
        if (p.render.by_element[e].empty()) continue;
        json list = json::array();
        for (const DisplayChoice& c : p.render.by_element[e])
          list.push_back({{"object", p.render.objects[c.object - 1u]}, {"min_similarity", c.min_similarity}});
        rules[p.options.palette.elements[e].name] = std::move(list);
      }
      body["render"] = {{"objects", std::move(objects)}, {"rules", std::move(rules)}, {"nothing_shown", display[0]}};
    }
    return body;
  }
};

}  // namespace

const JobMode& palette_mode() {
  static const PaletteMode mode;
  return mode;
}

}  // namespace voxd::api
