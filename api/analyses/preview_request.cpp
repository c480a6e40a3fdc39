// A shaded preview from one of six views.
#include "api/analyses/analysis_kind.h"
#include "api/slice_options.h"

namespace voxd::api {
namespace {

// A preview's size: a thumbnail is 16 pixels; past 65536 (the longest
// grid axis) nothing shrinks.
constexpr std::int64_t kSmallest = 16, kLargest = 65536;

std::string size_text(const AnalysisRequest& r) { return r.size == 0 ? "full" : std::to_string(r.size); }

class PreviewRequest final : public AnalysisKindRequest {
 public:
  AnalysisKind kind() const override { return AnalysisKind::preview; }

  void parse(FieldReader& in, AnalysisRequest& r) const override {
    in.allow({"view", "colour", "size", kSliceName});
    r.view = in.choice("view", {"+x", "-x", "+y", "-y", "+z", "-z"}, "+z");
    r.colour = in.choice("colour", {"none", "thickness", "distance", kSliceName}, "none");
    in.slice(r);
    if (const std::string* size = in.find("size")) {
      const auto n = parse_number<std::int64_t>(*size);
      if (*size == "full") r.size = 0;
      else if (n && *n >= kSmallest && *n <= kLargest) r.size = *n;
      else in.error("size", "must be the image's longest side in pixels, from " + std::to_string(kSmallest) + " to " +
                                std::to_string(kLargest) + ", or full (one pixel a voxel), got '" + *size + "'");
    }
  }

  // The sign escaped: a '+' in a URL query reads as a space. The size shows
  // only when asked for (as peeling does), so a preview's URL, key and the
  // CLI's file name are what they were before it had one.
  std::string query(const AnalysisRequest& r) const override {
    return "view=" + std::string(r.view[0] == '+' ? "%2B" : "-") + r.view.substr(1) + "&colour=" + r.colour +
           (r.size != AnalysisRequest::kDefaultPreviewSize ? "&size=" + size_text(r) : "") + r.slice_query();
  }

  void add_json(const AnalysisRequest& r, nlohmann::json& j) const override {
    j.update({{"view", r.view}, {"colour", r.colour}});
    if (r.size == 0) j["size"] = "full";
    else if (r.size != AnalysisRequest::kDefaultPreviewSize) j["size"] = r.size;
    if (r.slice_coloured()) j[kSliceName] = nlohmann::json::parse(r.slice_json);
  }

  const char* content_type(const AnalysisRequest&) const override { return "image/png"; }
};

}  // namespace

const AnalysisKindRequest& preview_request() {
  static const PreviewRequest kind;
  return kind;
}

}  // namespace voxd::api
