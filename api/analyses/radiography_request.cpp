// A radiograph along an axis: thickness per ray as a PNG or its statistics.
#include "api/analyses/analysis_kind.h"

namespace voxd::api {
namespace {

class RadiographyRequest final : public AnalysisKindRequest {
 public:
  AnalysisKind kind() const override { return AnalysisKind::radiography; }

  void parse(FieldReader& in, AnalysisRequest& r) const override {
    in.allow({"axis", "measure", "format", "unit", "peel", "peel_metric"});
    r.axis = in.axis();
    in.peel(r);
    r.measure = in.choice("measure", kRadiographyMeasureNames, RadiographyMeasure::max);
    r.format = in.choice("format", {"png16", "png", "json"}, "png16");
    r.unit = in.choice("unit", {"voxels", "model"}, "voxels");
  }

  std::string query(const AnalysisRequest& r) const override {
    return "axis=" + axis_name(r.axis) + "&measure=" + to_string(r.measure) + "&format=" + r.format + "&unit=" + r.unit +
           r.peel_query();
  }

  void add_json(const AnalysisRequest& r, nlohmann::json& j) const override {
    j.update({{"axis", axis_name(r.axis)}, {"measure", to_string(r.measure)}, {"format", r.format}, {"unit", r.unit},
              {"peel", r.peel}, {"peel_metric", to_string(r.peel_metric)}});
  }

  const char* content_type(const AnalysisRequest& r) const override {
    return r.format == "json" ? "application/json" : "image/png";
  }
};

}  // namespace

const AnalysisKindRequest& radiography_request() {
  static const RadiographyRequest kind;
  return kind;
}

}  // namespace voxd::api
