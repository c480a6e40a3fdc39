// The analysis requests shared by the job JSON and the result routes:
// defaults, canonical queries and keys, and every kind of bad input.
#include <gtest/gtest.h>

#include <set>

#include <nlohmann/json.hpp>

#include "api/analysis_request.h"
#include "api/job_params.h"
#include "api/param_error.h"

namespace voxd::api {
namespace {

using nlohmann::json;

std::set<std::string> error_paths(const std::function<void()>& f) {
  std::set<std::string> paths;
  try {
    f();
    ADD_FAILURE() << "expected InvalidParams";
  } catch (const InvalidParams& e) {
    for (const auto& err : e.errors()) {
      EXPECT_GT(err.message.size(), 10u) << err.path;
      paths.insert(err.path);
    }
  }
  return paths;
}

TEST(AnalysisRequest, DefaultsAreSpelledOutInTheCanonicalQuery) {
  EXPECT_EQ(parse_analysis_request(AnalysisKind::radiography, {}, "").query(), "axis=z&measure=max&format=png16&unit=voxels");
  EXPECT_EQ(parse_analysis_request(AnalysisKind::analysis, {}, "").query(), "cleanup=none&thickness=true");
  EXPECT_EQ(parse_analysis_request(AnalysisKind::preview, {}, "").query(), "view=%2Bz&colour=none");
  EXPECT_EQ(parse_analysis_request(AnalysisKind::thickness, {}, "").query(), "measure=wall&format=nrrd&unit=model");
  EXPECT_EQ(parse_analysis_request(AnalysisKind::thickness, {{"measure", "local"}}, "").query(),
            "measure=local&format=nrrd&unit=model");
  EXPECT_EQ(parse_analysis_request(AnalysisKind::section, {{"index", "7"}, {"axis", "x"}}, "").query(),
            "axis=x&index=7&colour=none");
  EXPECT_EQ(parse_analysis_request(AnalysisKind::analysis, {{"max_wall", "2.50"}, {"min_wall", "0.8"}}, "").query(),
            "cleanup=none&thickness=true&min_wall=0.8&max_wall=2.5");
}

TEST(AnalysisRequest, TheSameRequestWrittenDifferentlyHasOneKey) {
  const auto a = parse_analysis_request(AnalysisKind::radiography, {{"unit", "voxels"}, {"axis", "z"}}, "");
  const auto b = parse_analysis_request(AnalysisKind::radiography, {}, "");
  EXPECT_EQ(a.artifact_key(), b.artifact_key());
  const auto plus = parse_analysis_request(AnalysisKind::preview, {{"view", "+x"}}, "");
  const auto space = parse_analysis_request(AnalysisKind::preview, {{"view", " x"}}, "");  // '+' decoded as a space
  const auto minus = parse_analysis_request(AnalysisKind::preview, {{"view", "-x"}}, "");
  EXPECT_EQ(plus.artifact_key(), space.artifact_key());
  EXPECT_NE(plus.artifact_key(), minus.artifact_key());
  for (const auto& r : {a, plus, minus, parse_analysis_request(AnalysisKind::section, {{"coordinate", "-1.25e-3"}}, "")}) {
    for (char c : r.artifact_key())
      EXPECT_TRUE(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.') << r.artifact_key();
  }
}

TEST(AnalysisRequest, EveryProblemIsReportedAtItsField) {
  EXPECT_EQ(error_paths([] {
              parse_analysis_request(AnalysisKind::radiography,
                                     {{"axis", "w"}, {"measure", "mean"}, {"format", "tiff"}, {"unit", "mm"}, {"zoom", "2"}}, "");
            }),
            (std::set<std::string>{"/axis", "/measure", "/format", "/unit", "/zoom"}));
  EXPECT_EQ(error_paths([] { parse_analysis_request(AnalysisKind::section, {{"axis", "z"}}, "/q"); }),
            (std::set<std::string>{"/q/index"}));
  EXPECT_EQ(error_paths([] { parse_analysis_request(AnalysisKind::section, {{"index", "1"}, {"coordinate", "2"}}, ""); }),
            (std::set<std::string>{"/index"}));
  EXPECT_EQ(error_paths([] { parse_analysis_request(AnalysisKind::section, {{"index", "-1"}}, ""); }),
            (std::set<std::string>{"/index"}));
  EXPECT_EQ(error_paths([] { parse_analysis_request(AnalysisKind::section, {{"index", "1.5"}}, ""); }),
            (std::set<std::string>{"/index"}));
  EXPECT_EQ(error_paths([] {
              parse_analysis_request(AnalysisKind::analysis, {{"min_wall", "0"}, {"max_wall", "nan"}, {"cleanup", "all"}}, "");
            }),
            (std::set<std::string>{"/min_wall", "/max_wall", "/cleanup"}));
  EXPECT_EQ(error_paths([] { parse_analysis_request(AnalysisKind::analysis, {{"min_wall", "1"}, {"thickness", "false"}}, ""); }),
            (std::set<std::string>{"/thickness"}));
  EXPECT_EQ(error_paths([] { parse_analysis_request(AnalysisKind::preview, {{"view", "up"}, {"view", "+z"}}, ""); }),
            (std::set<std::string>{"/view"}));
}

// Issue #39: a preview is at most `size` pixels along its longest side
// (2048 by default), or one pixel a voxel with size=full.
TEST(AnalysisRequest, APreviewsSizeIsPixelsOrFull) {
  EXPECT_EQ(parse_analysis_request(AnalysisKind::preview, {}, "").size, 2048);
  // The default shows nowhere, as before previews had a size.
  EXPECT_EQ(parse_analysis_request(AnalysisKind::preview, {{"size", "2048"}}, "").query(), "view=%2Bz&colour=none");
  EXPECT_FALSE(to_json(parse_analysis_request(AnalysisKind::preview, {}, "")).contains("size"));
  EXPECT_EQ(parse_analysis_request(AnalysisKind::preview, {{"size", "full"}}, "").size, 0);
  const AnalysisRequest small = parse_analysis_request(AnalysisKind::preview, {{"size", "300"}, {"view", "-x"}}, "");
  EXPECT_EQ(small.size, 300);
  EXPECT_EQ(small.query(), "view=-x&colour=none&size=300");
  EXPECT_EQ(parse_analysis_request(AnalysisKind::preview, {{"size", "full"}}, "").query(), "view=%2Bz&colour=none&size=full");
  EXPECT_EQ(to_json(small), json::parse(R"({"kind":"preview","view":"-x","colour":"none","size":300})"));
  for (const char* bad : {"0", "15", "65537", "1.5", "big", "", "-20"}) {
    try {
      parse_analysis_request(AnalysisKind::preview, {{"size", bad}}, "/q");
      ADD_FAILURE() << bad;
    } catch (const InvalidParams& e) {
      ASSERT_EQ(e.errors().size(), 1u);
      EXPECT_EQ(e.errors()[0].path, "/q/size");
      EXPECT_EQ(e.errors()[0].message, std::string("must be the image's longest side in pixels, from 16 to 65536, or full "
                                                   "(one pixel a voxel), got '") + bad + "'");
    }
  }
  // Only previews take it.
  EXPECT_EQ(error_paths([] { parse_analysis_request(AnalysisKind::section, {{"index", "1"}, {"size", "100"}}, ""); }),
            (std::set<std::string>{"/size"}));
  // In the job JSON, a number or "full".
  const JobParams p = parse_job_params(json::parse(R"({"grid":{"resolution":32},"analyses":[
      {"kind":"preview","size":512},{"kind":"preview","size":"full"}]})"));
  ASSERT_EQ(p.analyses.size(), 2u);
  EXPECT_EQ(p.analyses[0].size, 512);
  EXPECT_EQ(p.analyses[1].size, 0);
  EXPECT_EQ(to_json(p.analyses[1]).at("size"), "full");
}

TEST(AnalysisRequest, JobJsonAnalysesAreTypedAndCheckedTogetherWithTheRest) {
  const JobParams p = parse_job_params(json::parse(R"({"grid":{"resolution":32},"analyses":[
      {"kind":"analysis","min_wall":0.8,"thickness":true},{"kind":"section","axis":"y","index":3,"colour":"thickness"},
      {"kind":"preview","view":"-y"}]})"));
  ASSERT_EQ(p.analyses.size(), 3u);
  EXPECT_EQ(p.analyses[0].min_wall, 0.8);
  EXPECT_EQ(p.analyses[1].axis, 1);
  EXPECT_EQ(p.analyses[1].index, 3);
  EXPECT_EQ(p.analyses[2].view, "-y");
  EXPECT_EQ(to_json(p.analyses[1]),
            json::parse(R"({"kind":"section","axis":"y","index":3,"colour":"thickness","peel":0,"peel_metric":"faces"})"));
  // Peeling shows in the query only when asked for.
  EXPECT_EQ(parse_analysis_request(AnalysisKind::section, {{"index", "1"}, {"peel", "2"}, {"peel_metric", "euclidean"}}, "").query(),
            "axis=z&index=1&colour=none&peel=2&peel_metric=euclidean");
  EXPECT_EQ(parse_analysis_request(AnalysisKind::analysis, {{"peel_metric", "euclidean"}}, "").query(),
            "cleanup=none&thickness=true&peel_metric=euclidean");
  // A grid error and analyses errors come back in one answer.
  EXPECT_EQ(error_paths([] {
              parse_job_params(json::parse(R"({"grid":{"resolution":0},"analyses":[
                  {"kind":"radiography","axis":2},{"axis":"x"},"preview",{"kind":"preview","view":["+z"]}]})"));
            }),
            (std::set<std::string>{"/grid/resolution", "/analyses/0/axis", "/analyses/1/kind", "/analyses/2",
                                   "/analyses/3/view"}));
  EXPECT_EQ(error_paths([] { parse_job_params(json::parse(R"({"analyses":{"kind":"preview"}})")); }),
            (std::set<std::string>{"/analyses"}));
  json many = json::array();
  for (int i = 0; i < 65; ++i) many.push_back({{"kind", "preview"}});
  EXPECT_EQ(error_paths([&] { parse_job_params(json{{"analyses", many}}); }), (std::set<std::string>{"/analyses"}));
}

}  // namespace
}  // namespace voxd::api
