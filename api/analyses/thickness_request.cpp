// The thickness volume: wall or local thickness per voxel.
#include "api/analyses/analysis_kind.h"

namespace voxd::api {
namespace {

class ThicknessRequest final : public AnalysisKindRequest {
 public:
  AnalysisKind kind() const override { return AnalysisKind::thickness; }

  void parse(FieldReader& in, AnalysisRequest& r) const override {
    in.allow({"measure", "format", "unit"});
    r.thickness_measure = in.choice("measure", kThicknessMeasureNames, ThicknessMeasure::wall);
    r.format = in.choice("format", {"nrrd", "raw", "rle"}, "nrrd");
    r.unit = in.choice("unit", {"model", "voxels"}, "model");
  }

  std::string query(const AnalysisRequest& r) const override {
    return "measure=" + std::string(to_string(r.thickness_measure)) + "&format=" + r.format + "&unit=" + r.unit;
  }

  void add_json(const AnalysisRequest& r, nlohmann::json& j) const override {
    j.update({{"measure", to_string(r.thickness_measure)}, {"format", r.format}, {"unit", r.unit}});
  }

  const char* content_type(const AnalysisRequest& r) const override {
    return r.format == "rle" ? "application/vnd.voxd.rle" : r.format == "nrrd" ? "application/x-nrrd" : "application/octet-stream";
  }
};

}  // namespace

const AnalysisKindRequest& thickness_request() {
  static const ThicknessRequest kind;
  return kind;
}

}  // namespace voxd::api
