// The thickness volume (wall or local thickness per voxel), or the same on
// the part's own mesh: ply, glb, or json (the values per vertex, their
// statistics over the surface, and the thin-region id of each vertex).
#include "api/analyses/analysis_kind.h"

namespace voxd::api {
namespace {

bool on_mesh(const AnalysisRequest& r) { return r.format == "ply" || r.format == "glb" || r.format == "json"; }

class ThicknessRequest final : public AnalysisKindRequest {
 public:
  AnalysisKind kind() const override { return AnalysisKind::thickness; }

  void parse(FieldReader& in, AnalysisRequest& r) const override {
    in.allow({"measure", "format", "unit", "min_wall", "max_wall"});
    r.thickness_measure = in.choice("measure", kThicknessMeasureNames, ThicknessMeasure::wall);
    r.format = in.choice("format", {"nrrd", "raw", "rle", "ply", "glb", "json"}, "nrrd");
    r.unit = in.choice("unit", {"model", "voxels"}, "model");
    r.min_wall = in.positive("min_wall");
    r.max_wall = in.positive("max_wall");
    if ((r.min_wall || r.max_wall) && !on_mesh(r))
      in.error(r.min_wall ? "min_wall" : "max_wall",
               "sets the colours and thin regions on the part's mesh: only with format=ply, glb or json");
    if (r.min_wall && r.max_wall && *r.max_wall <= *r.min_wall)
      in.error("max_wall", "must be more than min_wall");
  }

  std::string query(const AnalysisRequest& r) const override {
    std::string q = "measure=" + std::string(to_string(r.thickness_measure)) + "&format=" + r.format + "&unit=" + r.unit;
    // In model units, as given: the same walls whatever `unit` the values take.
    if (r.min_wall) q += "&min_wall=" + number_text(*r.min_wall);
    if (r.max_wall) q += "&max_wall=" + number_text(*r.max_wall);
    return q;
  }

  void add_json(const AnalysisRequest& r, nlohmann::json& j) const override {
    j.update({{"measure", to_string(r.thickness_measure)}, {"format", r.format}, {"unit", r.unit}});
    if (r.min_wall) j["min_wall"] = *r.min_wall;
    if (r.max_wall) j["max_wall"] = *r.max_wall;
  }

  const char* content_type(const AnalysisRequest& r) const override {
    if (r.format == "ply") return "application/x-ply";
    if (r.format == "glb") return "model/gltf-binary";
    if (r.format == "json") return "application/json";
    return r.format == "rle" ? "application/vnd.voxd.rle" : r.format == "nrrd" ? "application/x-nrrd" : "application/octet-stream";
  }
};

}  // namespace

const AnalysisKindRequest& thickness_request() {
  static const ThicknessRequest kind;
  return kind;
}

}  // namespace voxd::api
