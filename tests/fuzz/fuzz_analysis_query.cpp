// libFuzzer harness for the analysis routes' query parser: the first byte
// picks the route (analysis, radiography, section, preview, thickness), the
// rest is a URL query "k=v&k=v" as the routes receive it.
#include <cstdint>
#include <string>
#include <string_view>

#include "api/analysis_request.h"
#include "api/param_error.h"
#include "voxd/error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  using voxd::api::AnalysisKind;
  const AnalysisKind kinds[] = {AnalysisKind::analysis, AnalysisKind::radiography, AnalysisKind::section,
                                AnalysisKind::preview, AnalysisKind::thickness};
  const AnalysisKind kind = kinds[data[0] % 5];
  const std::string_view query(reinterpret_cast<const char*>(data + 1), size - 1);
  voxd::api::Fields fields;
  std::size_t start = 0;
  while (start <= query.size()) {
    const std::size_t end = std::min(query.find('&', start), query.size());
    const std::string_view pair = query.substr(start, end - start);
    const std::size_t eq = pair.find('=');
    fields.emplace_back(std::string(pair.substr(0, eq)), eq == std::string_view::npos ? "" : std::string(pair.substr(eq + 1)));
    start = end + 1;
  }
  try {
    const voxd::api::AnalysisRequest r = voxd::api::parse_analysis_request(kind, fields, "");
    (void)r.artifact_key();
    const std::string query = r.query();
    // A slice function's canonical JSON reads back to itself: the same
    // function, the same query, the same key.
    if (r.slice_coloured()) {
      voxd::api::Fields again = fields;
      for (auto& [k, v] : again)
        if (k == "slice") v = r.slice_json;
      const voxd::api::AnalysisRequest back = voxd::api::parse_analysis_request(kind, again, "");
      if (back.slice_json != r.slice_json || back.query() != query) __builtin_trap();
    }
  } catch (const voxd::api::InvalidParams&) {
  } catch (const voxd::Error&) {
  }
  return 0;
}
