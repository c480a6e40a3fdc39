// A section: one voxel layer across an axis, at an index or a coordinate.
#include "api/analyses/analysis_kind.h"
#include "api/slice_options.h"

namespace voxd::api {
namespace {

class SectionRequest final : public AnalysisKindRequest {
 public:
  AnalysisKind kind() const override { return AnalysisKind::section; }

  void parse(FieldReader& in, AnalysisRequest& r) const override {
    in.allow({"axis", "index", "coordinate", "colour", "peel", "peel_metric", kSliceName});
    r.axis = in.axis();
    in.peel(r);
    r.index = in.count("index");
    r.coordinate = in.finite("coordinate");
    r.colour = in.choice("colour", {"none", "thickness", "distance", kSliceName}, "none");
    in.slice(r);
    if (r.index.has_value() == r.coordinate.has_value() && in.ok())
      in.error("index", "give exactly one of index (voxel layer) or coordinate (model units)");
  }

  std::string query(const AnalysisRequest& r) const override {
    return "axis=" + axis_name(r.axis) +
           (r.index ? "&index=" + std::to_string(*r.index) : "&coordinate=" + number_text(*r.coordinate)) +
           "&colour=" + r.colour + r.peel_query() + r.slice_query();
  }

  void add_json(const AnalysisRequest& r, nlohmann::json& j) const override {
    j["axis"] = axis_name(r.axis);
    if (r.index) j["index"] = *r.index;
    if (r.coordinate) j["coordinate"] = *r.coordinate;
    j["colour"] = r.colour;
    j["peel"] = r.peel;
    j["peel_metric"] = to_string(r.peel_metric);
    if (r.slice_coloured()) j[kSliceName] = nlohmann::json::parse(r.slice_json);
  }

  const char* content_type(const AnalysisRequest&) const override { return "image/png"; }
};

}  // namespace

const AnalysisKindRequest& section_request() {
  static const SectionRequest kind;
  return kind;
}

}  // namespace voxd::api
