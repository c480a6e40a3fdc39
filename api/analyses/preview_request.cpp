// A shaded preview from one of six views.
#include "api/analyses/analysis_kind.h"

namespace voxd::api {
namespace {

class PreviewRequest final : public AnalysisKindRequest {
 public:
  AnalysisKind kind() const override { return AnalysisKind::preview; }

  void parse(FieldReader& in, AnalysisRequest& r) const override {
    in.allow({"view", "colour"});
    r.view = in.choice("view", {"+x", "-x", "+y", "-y", "+z", "-z"}, "+z");
    r.colour = in.choice("colour", {"none", "thickness", "distance"}, "none");
  }

  // The sign escaped: a '+' in a URL query reads as a space.
  std::string query(const AnalysisRequest& r) const override {
    return "view=" + std::string(r.view[0] == '+' ? "%2B" : "-") + r.view.substr(1) + "&colour=" + r.colour;
  }

  void add_json(const AnalysisRequest& r, nlohmann::json& j) const override {
    j.update({{"view", r.view}, {"colour", r.colour}});
  }

  const char* content_type(const AnalysisRequest&) const override { return "image/png"; }
};

}  // namespace

const AnalysisKindRequest& preview_request() {
  static const PreviewRequest kind;
  return kind;
}

}  // namespace voxd::api
