// The analysis report (kind "analysis"): clean-up, wall thickness and its
// thresholds, skin removal, how peel layers are counted.
#include "api/analyses/analysis_kind.h"

namespace voxd::api {
namespace {

class ReportRequest final : public AnalysisKindRequest {
 public:
  AnalysisKind kind() const override { return AnalysisKind::analysis; }

  void parse(FieldReader& in, AnalysisRequest& r) const override {
    in.allow({"cleanup", "thickness", "skin", "min_wall", "max_wall", "peel_metric"});
    r.peel_metric = in.choice("peel_metric", kPeelMetricNames, PeelMetric::faces);
    r.cleanup = in.choice("cleanup", {"none", "debris", "sheets"}, "none");
    r.thickness = in.flag("thickness", true);
    r.skin = in.flag("skin", true);
    r.min_wall = in.positive("min_wall");
    r.max_wall = in.positive("max_wall");
    if ((r.min_wall || r.max_wall) && !r.thickness)
      in.error("thickness", "min_wall and max_wall need the thickness analysis; drop thickness=false");
  }

  std::string query(const AnalysisRequest& r) const override {
    std::string q = "cleanup=" + r.cleanup + "&thickness=" + (r.thickness ? "true" : "false");
    if (r.min_wall) q += "&min_wall=" + number_text(*r.min_wall);
    if (r.max_wall) q += "&max_wall=" + number_text(*r.max_wall);
    if (r.peel_metric != PeelMetric::faces) q += std::string("&peel_metric=") + to_string(r.peel_metric);
    if (!r.skin) q += "&skin=false";  // after the rest, so URLs of earlier releases stay the same
    return q;
  }

  void add_json(const AnalysisRequest& r, nlohmann::json& j) const override {
    j["peel_metric"] = to_string(r.peel_metric);
    j["cleanup"] = r.cleanup;
    j["thickness"] = r.thickness;
    j["skin"] = r.skin;
    if (r.min_wall) j["min_wall"] = *r.min_wall;
    if (r.max_wall) j["max_wall"] = *r.max_wall;
  }

  const char* content_type(const AnalysisRequest&) const override { return "application/json"; }
};

}  // namespace

const AnalysisKindRequest& report_request() {
  static const ReportRequest kind;
  return kind;
}

}  // namespace voxd::api
